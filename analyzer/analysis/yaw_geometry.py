"""Angles on the circle: the shortest signed difference, and yaw seen from north or from the nose.

The attitude feedback gives two yaws: ``psi``, the gimbal's geomagnetic yaw (0..360,
from north), and ``Motor_psi``, the yaw motor's angle from the airframe's nose (+-170,
+-325 on the 3.5x models). A gimbal that knows the aircraft's heading reports
``psi = heading + Motor_psi``; one that does not reports ``psi = Motor_psi``.
"""

from __future__ import annotations

from analyzer.analysis.samples import MOTOR_YAW, PITCH, Sample

FULL_TURN = 360.0
HALF_TURN = 180.0


def shortest_difference(a: float, b: float) -> float:
    """``a - b`` the shortest way round the circle, in (-180, 180]."""
    d = (a - b) % FULL_TURN
    return d - FULL_TURN if d > HALF_TURN else d


def as_motor_angle(angle: float) -> float:
    """An angle as the motor would name it: in (-180, 180] (200 is -160)."""
    return shortest_difference(angle, 0.0)


def psi_offset(sample: Sample) -> float:
    """``psi - Motor_psi``: the heading the gimbal uses (0 when it has none), in (-180, 180]."""
    return shortest_difference(sample.yaw, sample.motor_yaw)


def motor_limit(sample: Sample) -> float:
    """How far the yaw motor turns either way (170, or 325 on the 3.5x zoom models)."""
    limits = sample.limits(MOTOR_YAW)
    assert limits is not None
    return limits[1]


def motor_target(axis: str, target: float, sample: Sample) -> float:
    """The motor angle, in (-180, 180], that points at ``target`` (of ``axis``) at ``sample``."""
    if axis == MOTOR_YAW:
        return as_motor_angle(target)
    return as_motor_angle(target - psi_offset(sample))


def reachable(axis: str, target: float, sample: Sample) -> bool:
    """Whether the yaw motor can point at ``target`` (pitch targets: always)."""
    if axis == PITCH:
        return True
    return abs(motor_target(axis, target, sample)) <= motor_limit(sample)


def angle_error(axis: str, target: float, sample: Sample) -> float:
    """Target minus the sample's angle: the shortest way round for yaw, in (-180, 180]."""
    if axis == PITCH:
        return target - sample.pitch
    return shortest_difference(target, sample.value(axis))


def travel(axis: str, target: float, sample: Sample) -> float:
    """The signed turn still needed from ``sample`` to ``target``, along the way the axis turns.

    Pitch turns along its range. Yaw turns the yaw motor, which cannot pass its back stop
    (+-170): from -100 to 120 it turns +220, not the -140 of the shortest way round. A
    motor that turns past 180 (+-325) takes the shortest way.
    """
    if axis == PITCH:
        return target - sample.pitch
    if motor_limit(sample) >= HALF_TURN:
        return angle_error(axis, target, sample)
    return motor_target(axis, target, sample) - sample.motor_yaw
