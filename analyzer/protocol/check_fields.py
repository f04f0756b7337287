"""The /check/steps event contract: the bench check's steps, verdicts and measured figures."""

from __future__ import annotations

# The built-in steps of `gimbal-analyzer check`, in the order they run.
STEP_NAMES = (
    "feedback",
    "forward",
    "pitch_angle",
    "yaw_airframe",
    "yaw_geodetic",
    "pan_speed",
    "tilt_speed",
    "look_down",
    "zoom",
    "tracking",
)

PASS = "pass"
FAIL = "fail"
SKIPPED = "skipped"
STEP_VERDICTS = (PASS, FAIL, SKIPPED)

# name -> (JSON type, description) of the figures a step may carry (absent when not measured).
FIGURES: dict[str, tuple[str, str]] = {
    "latency_s": (
        "number",
        "seconds from the command to the first motion, extrapolated back from the first "
        "feedback samples in motion",
    ),
    "slew_dps": (
        "number",
        "speed of a move to an angle, deg/s, fitted to the feedback samples in the moving "
        "part (not the end points)",
    ),
    "rate_dps": (
        "number",
        "speed-control steps: the rate the gimbal turned at, deg/s: the response analysis' "
        "(its measured share of the speed asked, late motion included), else fitted to the "
        "feedback while the speed held",
    ),
    "asked_dps": ("number", "speed-control steps: the speed the commands asked for, deg/s"),
    "overshoot_deg": ("number", "how far the angle went past the target, degrees"),
    "settle_s": (
        "number",
        "seconds from the command to the feedback sample from which the angle stays within "
        "the tolerance of where it ended",
    ),
    "error_deg": ("number", "target minus the final angle, degrees (yaw: the short way round)"),
    "target_deg": ("number", "the angle asked for, as the command gave it"),
    "axis": ("string", "the axis measured: pitch, yaw (from north) or motor_yaw (from the nose)"),
    "period_s": ("number", "feedback step: median time between feedback messages"),
    "lost": ("integer", "feedback step: feedback messages missing from the 500 ms rhythm"),
    "crc_errors": ("integer", "feedback step: CRC errors and incomplete feedback messages"),
    "messages": ("integer", "feedback step: feedback messages received"),
    "tries": (
        "integer",
        "how many times the step ran, when more than once: a step the feedback did not allow "
        "to be judged (messages lost or damaged during it) is run again from its start, at "
        "most 3 times",
    ),
    "scale": (
        "number",
        "zoom step: the picture's scale after the zoom in over before it (> 1: zoomed in), "
        "measured in the recorded video",
    ),
    "scale_back": (
        "number",
        "zoom step: the picture's scale after zoom_1x over before it, measured in the video",
    ),
}

# The other fields of a /check/steps event: name -> (JSON type, description).
STEP_FIELDS: dict[str, tuple[str, str]] = {
    "step": ("string", "the step's name"),
    "verdict": ("string", "pass, fail, or skipped when it cannot be judged from the feedback"),
    "detail": ("string", "why, in one line"),
    "index": ("integer", "the step's place in this run, from 1"),
    "started_at": ("number", "time (Unix seconds) the step sent its first command"),
    "duration_s": ("number", "how long the step took"),
    "findings": (
        "array",
        "the /analysis/response verdicts the step was judged on, as 'command check: verdict'",
    ),
}
REQUIRED_FIELDS = ("step", "verdict", "detail")
