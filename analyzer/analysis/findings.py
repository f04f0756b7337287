"""A finding of the response analysis: one command judged against the feedback, as an event."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from analyzer.protocol.types import TOPIC_ANALYSIS_RESPONSE, Event

OBEYED = "obeyed"
PARTIAL = "partial"
NOT_OBEYED = "not_obeyed"
UNKNOWN = "unknown"
VERDICTS = (OBEYED, PARTIAL, NOT_OBEYED, UNKNOWN)
_RANK = {OBEYED: 0, UNKNOWN: 1, PARTIAL: 2, NOT_OBEYED: 3}

# What was checked (the ``check`` field).
CHECK_TARGET = "target"  # specified_angle / look_down / forward: reach an angle
CHECK_RATE = "rate"  # gimbal_control: measured against commanded speed
CHECK_STOP = "stop"  # gimbal_control: stopped when the commands stopped
CHECK_REPEAT = "repeat"  # gimbal_control: repeated often enough to keep moving
CHECK_TRACKING = "tracking"  # tracking / tracking_stop against the tracking flag
CHECK_LIMIT = "limit"  # a mechanical limit reached
CHECK_FEEDBACK = "feedback"  # feedback health over a minute
CHECK_FEEDBACK_GAP = "feedback_gap"  # a silence in the feedback
CHECKS = (
    CHECK_TARGET,
    CHECK_RATE,
    CHECK_STOP,
    CHECK_REPEAT,
    CHECK_TRACKING,
    CHECK_LIMIT,
    CHECK_FEEDBACK,
    CHECK_FEEDBACK_GAP,
)
FEEDBACK_COMMAND = "feedback"  # the ``command`` of findings about the feedback itself
SOURCE = "analysis"


def worst(*verdicts: str) -> str:
    """The verdict that says the least good about the gimbal."""
    return max(verdicts, key=lambda v: _RANK[v])


@dataclass
class Finding:
    """One judgement; ``extra`` holds the optional numbers of the schema below."""

    command: str
    time: float
    check: str
    verdict: str
    detail: str
    extra: dict[str, Any] = field(default_factory=dict)

    def to_event(self) -> Event:
        fields: dict[str, Any] = {
            "command": self.command,
            "check": self.check,
            "verdict": self.verdict,
            "detail": self.detail,
        }
        for key, value in self.extra.items():
            if value is None:
                continue  # absent rather than null
            fields[key] = round(value, 3) if isinstance(value, float) else value
        return Event(TOPIC_ANALYSIS_RESPONSE, self.time, SOURCE, fields)


# name -> (JSON type, description) of the optional fields a finding may carry.
OPTIONAL_FIELDS: dict[str, tuple[str, str]] = {
    "axis": ("string", "pitch, yaw (north-referenced), motor_yaw (airframe) or several, '+'"),
    "target_deg": ("number", "target angle of a target-type command"),
    "response_s": ("number", "seconds from the command to the first feedback within tolerance"),
    "error_deg": ("number", "final error: target minus the last angle in the time allowed"),
    "overshoot_deg": ("number", "how far the angle went past the target"),
    "start_deg": ("number", "angle in the last feedback before the command"),
    "final_deg": ("number", "angle in the last feedback judged"),
    "yaw_reference": ("string", "north (flight controller attitude present) or airframe"),
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
    "gaps": ("integer", "silences over 1 s in the window"),
    "crc_errors": ("integer", "CRC errors and incomplete feedback messages in the window"),
    "window_s": ("number", "length of the health window"),
}


def verdict_line(counts: dict[str, int]) -> str:
    """'3 obeyed, 1 partial, 2 not obeyed, 0 unknown' in a fixed order."""
    return ", ".join(f"{counts.get(v, 0)} {v.replace('_', ' ')}" for v in VERDICTS)
