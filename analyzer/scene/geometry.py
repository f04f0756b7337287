"""Rotations as quaternions (x, y, z, w) and local east/north/up metres, in Foxglove's z-up frames.

Frames follow ROS REP 103: the world is east/north/up, a body is x forward, y left, z up;
an optical frame is x right, y down, z forward (into the picture).
"""

from __future__ import annotations

import math
from typing import NamedTuple

EARTH_RADIUS_M = 6_371_008.8  # mean radius: metres per radian along a great circle


class Quaternion(NamedTuple):
    x: float
    y: float
    z: float
    w: float


class Vector(NamedTuple):
    x: float
    y: float
    z: float


IDENTITY = Quaternion(0.0, 0.0, 0.0, 1.0)
# body (x forward, y left, z up) -> optical (x right, y down, z forward)
OPTICAL = Quaternion(-0.5, 0.5, -0.5, 0.5)


def axis_angle(axis: Vector, angle_rad: float) -> Quaternion:
    s = math.sin(angle_rad / 2)
    return Quaternion(axis.x * s, axis.y * s, axis.z * s, math.cos(angle_rad / 2))


def multiply(a: Quaternion, b: Quaternion) -> Quaternion:
    """``a`` then ``b`` in ``a``'s rotated frame (the Hamilton product a*b)."""
    return Quaternion(
        a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
        a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
        a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w,
        a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
    )


def rotate(q: Quaternion, v: Vector) -> Vector:
    """``v`` of the rotated frame expressed in the parent frame."""
    p = multiply(multiply(q, Quaternion(v.x, v.y, v.z, 0.0)), Quaternion(-q.x, -q.y, -q.z, q.w))
    return Vector(p.x, p.y, p.z)


X_AXIS = Vector(1.0, 0.0, 0.0)
Y_AXIS = Vector(0.0, 1.0, 0.0)
Z_AXIS = Vector(0.0, 0.0, 1.0)


def yaw_pitch_roll(yaw_rad: float, pitch_rad: float, roll_rad: float) -> Quaternion:
    """Rotation about z by yaw, then about the new y by pitch, then about the new x by roll."""
    return multiply(
        multiply(axis_angle(Z_AXIS, yaw_rad), axis_angle(Y_AXIS, pitch_rad)),
        axis_angle(X_AXIS, roll_rad),
    )


def aircraft_rotation(heading_deg: float, pitch_deg: float, roll_deg: float) -> Quaternion:
    """The aircraft's body in the east/north/up world from its attitude as aircraft report it:
    heading clockwise from north, pitch positive nose up, roll positive right wing down."""
    return yaw_pitch_roll(
        math.radians(90.0 - heading_deg), math.radians(-pitch_deg), math.radians(roll_deg)
    )


def gimbal_rotation(azimuth_deg: float, elevation_deg: float) -> Quaternion:
    """The gimbal's frame under its mount: x along the line of sight, turned ``azimuth_deg``
    clockwise seen from above (the yaw motor's angle) and raised ``elevation_deg`` (pitch).

    ``yaw_pitch_roll`` without a roll, multiplied out (this runs with every feedback): the
    very floats the products give, a zero as +0.0 as their sums make it."""
    half_yaw, half_pitch = math.radians(-azimuth_deg) / 2, math.radians(-elevation_deg) / 2
    sz, cz = math.sin(half_yaw), math.cos(half_yaw)
    sy, cy = math.sin(half_pitch), math.cos(half_pitch)
    return Quaternion(-sz * sy + 0.0, cz * sy + 0.0, sz * cy + 0.0, cz * cy)


def azimuth_elevation(v: Vector) -> tuple[float, float]:
    """A direction's azimuth (degrees clockwise from the frame's x axis, seen from above)
    and elevation (degrees above the x-y plane)."""
    return (
        math.degrees(math.atan2(-v.y, v.x)),
        math.degrees(math.atan2(v.z, math.hypot(v.x, v.y))),
    )


def east_north(
    lat0_deg: float, lon0_deg: float, lat_deg: float, lon_deg: float
) -> tuple[float, float]:
    """East and north metres of a position from a nearby origin (flat earth, fine for a flight)."""
    north = math.radians(lat_deg - lat0_deg) * EARTH_RADIUS_M
    east = math.radians(lon_deg - lon0_deg) * EARTH_RADIUS_M * math.cos(math.radians(lat0_deg))
    return east, north
