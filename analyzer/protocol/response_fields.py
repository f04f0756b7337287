"""The /analysis/response event contract: verdicts, checks and the fields a finding may carry."""

from __future__ import annotations

from typing import Any

OBEYED = "obeyed"
PARTIAL = "partial"
NOT_OBEYED = "not_obeyed"
UNKNOWN = "unknown"
VERDICTS = (OBEYED, PARTIAL, NOT_OBEYED, UNKNOWN)  # of a command's findings
# The feedback's own findings (command "feedback") say how healthy the link is instead:
# healthy, degraded (late, damaged or lost messages in the window), lost (a silence that
# lost messages, or no feedback in a window), unknown (no feedback in the whole input).
HEALTHY = "healthy"
DEGRADED = "degraded"
LOST = "lost"
HEALTH_VERDICTS = (HEALTHY, DEGRADED, LOST, UNKNOWN)
ALL_VERDICTS = (*VERDICTS, HEALTHY, DEGRADED, LOST)

# What was checked (the ``check`` field).
CHECK_TARGET = "target"  # specified_angle / look_down / forward: reach an angle
CHECK_RATE = "rate"  # gimbal_control: a stick movement's motion against the commanded
CHECK_STOP = "stop"  # gimbal_control: held still while the stick was centred
CHECK_REPEAT = "repeat"  # gimbal_control: a stream repeated too slowly to keep it moving
CHECK_TRACKING = "tracking"  # a tracking session's start, or its stop, against the flag
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
    "commanded_pan_dps": ("number", "mean commanded pan speed of a stick movement, deg/s"),
    "commanded_tilt_dps": ("number", "mean commanded tilt speed of a stick movement, deg/s"),
    "measured_pan_dps": (
        "number",
        "mean pan speed measured from the motor yaw feedback over the movement, deg/s",
    ),
    "measured_tilt_dps": (
        "number",
        "mean tilt speed measured from the pitch feedback over the movement, deg/s",
    ),
    "pan_ratio": (
        "number",
        "a stick movement's measured pan motion (motor yaw) over the motion its commanded "
        "speeds add up to, fitted over the feedback intervals at the best lag",
    ),
    "tilt_ratio": ("number", "the same for tilt (pitch)"),
    "rate_ratio": ("number", "pan_ratio or tilt_ratio, the one furthest from 1"),
    "peak_pan_dps": ("number", "the fastest pan speed a stick movement commanded, deg/s"),
    "peak_tilt_dps": ("number", "the fastest tilt speed a stick movement commanded, deg/s"),
    "lag_s": ("number", "how late the gimbal followed the commanded motion (best fit)"),
    "duration_s": (
        "number",
        "how long the stick movement (or the silence, the drift, the tracking session) lasted",
    ),
    "command_count": (
        "integer",
        "commands judged together: a stick movement's, a target's re-sends, a tracking "
        "session's box updates",
    ),
    "interval_mean_s": ("number", "mean time between the commands of a stick movement"),
    "interval_max_s": ("number", "longest time between the commands of a stick movement"),
    "component": ("string", "gimbal or dual_sensor: whose gimbal_control stream it was"),
    "resent_for_s": ("number", "how long a ground station re-sent the same target"),
    "updates_hz": ("number", "box updates per second of a tracking session"),
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
FIELD_ENUMS: dict[str, tuple[str, ...]] = {
    "yaw_reference": YAW_REFERENCES,
    "component": ("gimbal", "dual_sensor"),
}


FEEDBACK_COMMAND = "feedback"  # the ``command`` of findings about the feedback itself
VERDICT_WORDS = {
    OBEYED: "obeyed",
    PARTIAL: "PARTIAL",
    NOT_OBEYED: "NOT OBEYED",
    UNKNOWN: "unknown",
}
# Findings about the feedback itself say how healthy the link is, not what was obeyed:
# their verdict is the health word, shown in capitals when it is bad.
HEALTH_WORDS = {HEALTHY: "healthy", DEGRADED: "DEGRADED", LOST: "LOST", UNKNOWN: "unknown"}


def verdict_word(fields: dict[str, Any]) -> str:
    """How the text report names a finding's verdict: the health word for the feedback."""
    verdict = str(fields["verdict"])
    if fields.get("command") == FEEDBACK_COMMAND:
        return HEALTH_WORDS.get(verdict, verdict)
    return VERDICT_WORDS.get(verdict, verdict)
