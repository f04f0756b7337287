"""The /analysis/response event contract: verdicts, checks and the fields a finding may carry."""

from __future__ import annotations

from typing import Any

OBEYED = "obeyed"
PARTIAL = "partial"
NOT_OBEYED = "not_obeyed"
UNKNOWN = "unknown"
VERDICTS = (OBEYED, PARTIAL, NOT_OBEYED, UNKNOWN)

# What was checked (the ``check`` field).
CHECK_TARGET = "target"  # specified_angle / look_down / forward: reach an angle
CHECK_RATE = "rate"  # gimbal_control: measured against commanded speed
CHECK_STOP = "stop"  # gimbal_control: stopped when the commands stopped
CHECK_REPEAT = "repeat"  # gimbal_control: repeated often enough to keep moving
CHECK_TRACKING = "tracking"  # tracking / tracking_stop against the tracking flag
CHECK_LIMIT = "limit"  # a mechanical limit reached
CHECK_FEEDBACK = "feedback"  # feedback health over a minute
CHECK_FEEDBACK_GAP = "feedback_gap"  # a silence in the feedback
CHECK_PICTURE = "picture"  # camera commands (zoom, palette, PiP) judged from the video
CHECKS = (
    CHECK_TARGET,
    CHECK_RATE,
    CHECK_STOP,
    CHECK_REPEAT,
    CHECK_TRACKING,
    CHECK_LIMIT,
    CHECK_FEEDBACK,
    CHECK_FEEDBACK_GAP,
    CHECK_PICTURE,
)

# The two references a yaw target is judged in (the ``yaw_reference`` field).
REFERENCE_NORTH = "north"  # the gimbal's geomagnetic yaw psi
REFERENCE_AIRFRAME = "airframe"  # the yaw motor angle Motor_psi, from the airframe's nose
YAW_REFERENCES = (REFERENCE_NORTH, REFERENCE_AIRFRAME)

# name -> (JSON type, description) of the optional fields a finding may carry.
OPTIONAL_FIELDS: dict[str, tuple[str, str]] = {
    "axis": ("string", "pitch, yaw (north-referenced), motor_yaw (airframe) or several, '+'"),
    "target_deg": ("number", "target angle of a target-type command, as the command gave it"),
    "response_s": ("number", "seconds from the command to the first feedback within tolerance"),
    "error_deg": (
        "number",
        "final error: target minus the last angle in the time allowed (yaw: the shortest way "
        "round, -180..180)",
    ),
    "overshoot_deg": ("number", "how far the angle went past the target"),
    "start_deg": ("number", "angle in the last feedback before the command"),
    "final_deg": ("number", "angle in the last feedback judged"),
    "yaw_reference": (
        "string",
        "the reference a yaw target was judged in: north (the feedback's geomagnetic yaw psi) "
        "or airframe (the yaw motor angle, from the nose)",
    ),
    "reference_reason": (
        "string",
        "why that reference: 'command DATA4 = 1', 'FF13 present', 'psi offset from motor "
        "yaw: 30.0 deg', 'capture shows no heading source; psi used', 'no FF13 on the bus; "
        "psi follows motor yaw'",
    ),
    "observed_at": ("number", "time (Unix seconds) of the feedback that decided the finding"),
    "commanded_pan_dps": ("number", "commanded pan speed, deg/s"),
    "commanded_tilt_dps": ("number", "commanded tilt speed, deg/s"),
    "measured_pan_dps": ("number", "pan rate measured from the motor yaw feedback, deg/s"),
    "measured_tilt_dps": ("number", "tilt rate measured from the pitch feedback, deg/s"),
    "rate_ratio": ("number", "measured over commanded rate, the axis furthest from 1"),
    "lag_s": ("number", "estimated delay before the gimbal started moving"),
    "duration_s": ("number", "how long the commands (or the silence, the drift) lasted"),
    "command_count": ("integer", "commands in the burst"),
    "interval_s": ("number", "mean time between repeated commands"),
    "max_interval_s": ("number", "longest time between repeated commands"),
    "moved_deg": ("number", "movement seen after the commands stopped"),
    "limit_deg": ("number", "the mechanical limit reached"),
    "gap_s": ("number", "length of a silence in the feedback"),
    "feedback_hz": ("number", "feedback messages per second in the window"),
    "gaps": (
        "integer",
        "silences in the window that lost feedback messages (1.5 feedback periods or more)",
    ),
    "lost_messages": (
        "integer",
        "feedback messages lost: in the silence, or in the window's silences; a silence lost "
        "round(silence / period) - 1 of them",
    ),
    "crc_errors": ("integer", "CRC errors and incomplete feedback messages in the window"),
    "window_s": ("number", "length of the health window"),
    # camera commands judged from the video (check "picture")
    "stream": ("string", "the camera stream judged: main for /camera/main"),
    "frame_before": ("number", "capture time (Unix seconds) of the frame before the command"),
    "frame_after": (
        "number",
        "capture time (Unix seconds) of the frame the command is judged by: after the zoom "
        "settled or was stopped, or after the palette / layout had its time to change",
    ),
    "scale": (
        "number",
        "the picture's scale after over before (> 1: zoomed in), with what the aircraft's "
        "motion explains (the ground coming nearer or going away) taken out",
    ),
    "raw_scale": (
        "number",
        "the picture's scale after over before as the picture shows it, when the aircraft's "
        "motion changed it",
    ),
    "expected_scale": (
        "number",
        "the scale an obedient camera shows: 2 for zoom_in_2x and tap_zoom, the ratio asked "
        "over the zoom before for an absolute zoom when that zoom is known",
    ),
    "centre_offset": (
        "number",
        "tap_zoom: how far from the picture's centre the tapped point ended, as a fraction "
        "of half the picture (0 in the centre, 1 at the edge)",
    ),
    "palette_changed": ("boolean", "palette: whether the thermal picture's colours changed"),
    "layout_changed": ("boolean", "pip_cycle: whether the picture-in-picture layout changed"),
}
# Optional fields whose value is one of a few words.
FIELD_ENUMS: dict[str, tuple[str, ...]] = {"yaw_reference": YAW_REFERENCES}


FEEDBACK_COMMAND = "feedback"  # the ``command`` of findings about the feedback itself
VERDICT_WORDS = {
    "obeyed": "obeyed",
    "partial": "PARTIAL",
    "not_obeyed": "NOT OBEYED",
    "unknown": "unknown",
}
# Findings about the feedback itself say how healthy the link is, not what was obeyed.
HEALTH_WORDS = {
    "obeyed": "healthy",
    "partial": "DEGRADED",
    "not_obeyed": "SILENT",
    "unknown": "unknown",
}
GAP_WORD = "LOST"


def verdict_word(fields: dict[str, Any]) -> str:
    """How the text report names a finding's verdict: in health words for the feedback."""
    verdict = str(fields["verdict"])
    if fields.get("command") != FEEDBACK_COMMAND:
        return VERDICT_WORDS.get(verdict, verdict)
    if fields.get("check") == CHECK_FEEDBACK_GAP:
        return GAP_WORD
    return HEALTH_WORDS.get(verdict, verdict)
