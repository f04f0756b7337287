"""Attitude feedback as samples: pitch, yaw from north, yaw motor, and their limits."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from analyzer.protocol.feedback import MOTOR_YAW_LIMIT, WIDE_MOTOR_YAW_TYPES
from analyzer.protocol.reassembly import LATE_SEGMENT

PITCH = "pitch"
YAW = "yaw"  # geomagnetic yaw psi: referenced to north
MOTOR_YAW = "motor_yaw"  # yaw motor angle: referenced to the airframe's nose

PITCH_LIMITS = (-110.0, 60.0)  # chapter 2.2, theta range
MOTOR_YAW_LIMITS = MOTOR_YAW_LIMIT / 100  # +-170 deg; +-325 on the 3.5x zoom models
WIDE_MOTOR_YAW = 325.0
AT_LIMIT_DEG = 0.5  # within this of a limit counts as "at the limit"


@dataclass(frozen=True, slots=True)
class Sample:
    """One attitude feedback message."""

    time: float
    pitch: float
    yaw: float
    motor_yaw: float
    tracking: bool
    gimbal_type: int
    late: bool = False  # its segments came far apart: its time is later than it measured

    def value(self, axis: str) -> float:
        if axis == PITCH:
            return self.pitch
        if axis == YAW:
            return self.yaw
        return self.motor_yaw

    def limits(self, axis: str) -> tuple[float, float] | None:
        """The mechanical limits of ``axis`` (None for north-referenced yaw, which wraps)."""
        if axis == PITCH:
            return PITCH_LIMITS
        if axis == MOTOR_YAW:
            wide = self.gimbal_type in WIDE_MOTOR_YAW_TYPES
            limit = WIDE_MOTOR_YAW if wide else MOTOR_YAW_LIMITS
            return (-limit, limit)
        return None

    def at_limit(self, axis: str) -> float | None:
        """The limit this sample sits at on ``axis``, if any."""
        limits = self.limits(axis)
        if limits is None:
            return None
        value = self.value(axis)
        for limit in limits:
            if abs(value - limit) <= AT_LIMIT_DEG:
                return limit
        return None


def _number(fields: dict[str, Any], name: str) -> float | None:
    value = fields.get(name)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value)


def sample_from(
    time: float, fields: dict[str, Any], warnings: list[str] | None = None
) -> Sample | None:
    """A /gimbal/attitude event's fields as a Sample; None when an angle is missing.
    ``warnings``: the event's, which say whether its segments came late."""
    pitch, yaw, motor = (_number(fields, n) for n in ("pitch_deg", "yaw_deg", "motor_yaw_deg"))
    if pitch is None or yaw is None or motor is None:
        return None
    # Labelled fields hold the raw number in X_code (or, in older recordings, in X itself).
    code = fields.get("gimbal_type_code", fields.get("gimbal_type"))
    return Sample(
        time,
        pitch,
        yaw,
        motor,
        bool(fields.get("tracking", False)),
        code if isinstance(code, int) and not isinstance(code, bool) else 0,
        bool(warnings) and any(w.startswith(LATE_SEGMENT) for w in warnings or ()),
    )
