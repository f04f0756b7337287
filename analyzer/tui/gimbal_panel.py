"""Gimbal state panel: attitude gauges, type and mode, last camera commands, feedback age."""

from __future__ import annotations

from rich.text import Text
from textual.widgets import Static

from analyzer.protocol.types import TOPIC_GIMBAL_ATTITUDE, Event
from analyzer.tui.formatting import compass, describe_params, format_age, short_age, value_bar
from analyzer.tui.state import MonitorState

PITCH_RANGE = (-110.0, 60.0)
YAW_RANGE = (0.0, 360.0)
MOTOR_YAW_RANGE = (-170.0, 170.0)
WIDE_MOTOR_YAW_RANGE = (-325.0, 325.0)  # 3.5x zoom gimbals
WIDE_MOTOR_YAW_TYPES = (3, 4)
BAR_WIDTH = 22


def _axis(label: str, value: float | None, low: float, high: float, note: str = "") -> Text:
    line = Text(f"{label:<10}")
    line.append("     —  " if value is None else f"{value:8.2f}°", style="bold")
    line.append("  ")
    line.append(value_bar(value, low, high, BAR_WIDTH), style="cyan")
    line.append(f" {low:g}..{high:g}", style="dim")
    if note:
        line.append(f" {note}", style="bold")
    return line


def _command_line(state: MonitorState, label: str, event: Event | None, width: int = 27) -> Text:
    """'zoom  zoom_in       0.25s': label, what was asked, how long ago, in ``width`` cells."""
    line = Text(f"{label:<6}", style="dim")
    room = width - 6 - 7
    if event is None:
        line.append(f"{'—':<{room + 7}}")
        return line
    name = str(event.fields.get("name", ""))
    params = describe_params(event)
    summary = f"{name} {params}".strip() if label == "move" else params or name
    if len(summary) > room:
        summary = summary[: room - 1] + "…"
    line.append(f"{summary:<{room}}", style="bold")
    line.append(f"{short_age(state.age(event)):>7}", style="dim")
    return line


def render_gimbal(state: MonitorState) -> Text:
    """The panel's text (also used by tests)."""
    att = state.attitude
    f = att.fields if att is not None else {}
    pitch = f.get("pitch_deg")
    yaw = f.get("yaw_deg")
    motor = f.get("motor_yaw_deg")
    gimbal_type = f.get("gimbal_type_code")
    motor_range = WIDE_MOTOR_YAW_RANGE if gimbal_type in WIDE_MOTOR_YAW_TYPES else MOTOR_YAW_RANGE
    lines = [
        _axis("pitch", pitch, *PITCH_RANGE),
        _axis("yaw", yaw, *YAW_RANGE, note=compass(yaw) if yaw is not None else ""),
        _axis("motor yaw", motor, *motor_range),
    ]
    info = Text("type ", style="dim")
    if att is None:
        info.append("—")
    else:
        info.append(str(f.get("gimbal_type") or "?"), style="bold")
        info.append(f" ({f.get('gimbal_type_code', '?')})  mode ", style="dim")
        info.append(str(f.get("control_mode") or "?"), style="bold")
        info.append("  tracking ", style="dim")
        tracking = bool(f.get("tracking"))
        info.append("YES" if tracking else "no", style="bold green" if tracking else "bold")
    lines.append(info)
    cmds = state.last_commands
    row = _command_line(state, "zoom", cmds.get("zoom"))
    row.append("  ")
    row.append_text(_command_line(state, "focus", cmds.get("focus")))
    lines.append(row)
    row = _command_line(state, "rec", cmds.get("recording"))
    row.append("  ")
    row.append_text(_command_line(state, "snap", cmds.get("snapshot")))
    lines.append(row)
    lines.append(_command_line(state, "move", cmds.get("motion"), 60))
    feedback = Text("feedback ", style="dim")
    age = state.feedback_age
    stale = state.feedback_stale
    feedback.append(
        f"{format_age(age)} ago" if age is not None else "none yet",
        style="bold white on red" if stale else "bold green",
    )
    rate = state.topic_rates.get(TOPIC_GIMBAL_ATTITUDE, 0.0)
    feedback.append(f"  {rate:.1f}/s  {state.feedback_count:,} messages", style="dim")
    if state.ranging is not None:
        rf = state.ranging.fields
        feedback.append("  ranging ", style="dim")
        if rf.get("success", True):
            feedback.append(f"{rf.get('distance_m', 0):.1f} m")
        else:
            feedback.append("no target")
    lines.append(feedback)
    text = Text("\n").join(lines)
    text.no_wrap = True
    text.overflow = "ellipsis"
    return text


class GimbalPanel(Static):
    """Redrawn from the state at the app's refresh rate, only when something changed."""

    DEFAULT_CSS = """
    GimbalPanel { border: round $primary; padding: 0 1; height: 10;
        text-wrap: nowrap; text-overflow: ellipsis; }
    """

    def on_mount(self) -> None:
        self.border_title = "Gimbal"

    def show(self, state: MonitorState) -> None:
        self.update(render_gimbal(state))
