"""Which group of the gimbal panel (zoom, focus, motion, ...) a command belongs to."""

from __future__ import annotations

from analyzer.protocol.types import Event

# Last command of each group shown in the gimbal panel.
COMMAND_GROUPS: dict[str, str] = {
    "zoom": "zoom",
    "digital_zoom": "zoom",
    "zoom_1x": "zoom",
    "tap_zoom": "zoom",
    "focus": "focus",
    "tap_focus": "focus",
    "recording": "recording",
    "snapshot": "snapshot",
    "gimbal_control": "motion",
    "specified_angle": "motion",
    "look_down": "motion",
    "forward": "motion",
    "tracking": "motion",
    "tracking_stop": "motion",
}


def command_group(event: Event) -> str:
    """The group of a command event; a motion command on the zoom axis counts as zoom."""
    group = COMMAND_GROUPS.get(str(event.fields.get("name", "")), "other")
    if group == "motion" and event.fields.get("axis") == "zoom":
        group = "zoom"
    return group
