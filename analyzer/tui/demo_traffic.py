"""Synthetic bus traffic to exercise the monitor headless: tests, load benchmark, screenshots."""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

from analyzer.protocol.codec import encode_command
from analyzer.protocol.feedback import encode_attitude, encode_ranging, segments
from analyzer.protocol.ids import (
    ALTITUDE_ID,
    CONTROL_ID,
    FEEDBACK_ID,
    GPS_ID,
    UAV_ATTITUDE_ID,
)
from analyzer.protocol.types import CanFrame
from analyzer.protocol.uav import encode_altitude, encode_gps, encode_text, encode_uav_attitude

FOREIGN_BASE_ID = 0x18FF5000  # foreign extended IDs used by the generator: base + 0..n-1

# (time offset in each 10 s cycle, command name, parameters)
CAMERA_SCRIPT: tuple[tuple[float, str, dict[str, Any]], ...] = (
    (1.0, "zoom", {"action": "zoom_in"}),
    (1.6, "zoom", {"action": "stop"}),
    (2.0, "focus", {"action": "auto_focus"}),
    (3.0, "recording", {"action": "start"}),
    (4.0, "snapshot", {"mode": "single"}),
    (5.0, "specified_angle", {"yaw_deg": 45.0}),
    (6.0, "specified_angle", {"pitch_deg": -45.0}),
    (8.5, "recording", {"action": "stop"}),
)


def _pose(t: float) -> tuple[float, float, float]:
    """A slow sweep: (pitch, yaw, motor yaw) in degrees at time ``t``."""
    pitch = -30.0 + 20.0 * math.sin(t / 7.0)
    yaw = (120.0 + 8.0 * t) % 360.0
    motor = 40.0 * math.sin(t / 11.0)
    return round(pitch, 2), round(yaw, 2), round(motor, 2)


def session(
    t0: float,
    seconds: float,
    *,
    foreign_per_s: float = 0.0,
    foreign_ids: int = 16,
    pan_hz: float = 20.0,
    uav_hz: float = 10.0,
) -> Iterator[CanFrame]:
    """Frames of a plausible session, in time order, starting at ``t0``.

    The ground station pans at ``pan_hz`` (gimbal_control) during the first half of
    every 10 s and runs the camera script; the gimbal answers with attitude feedback
    every 0.5 s (four segments) and a laser ranging message every 2 s; the UAV sends
    GPS, altitude and attitude at ``uav_hz`` and a text every 5 s; other equipment adds
    ``foreign_per_s`` frames spread over ``foreign_ids`` foreign IDs with counters.
    """
    timeline = _Timeline(seconds)
    _ground_station(timeline, pan_hz)
    _gimbal(timeline)
    if uav_hz > 0:
        _uav(timeline, uav_hz)
    if foreign_per_s > 0:
        n = int(seconds * foreign_per_s)
        for k in range(n):
            index = k % foreign_ids
            counter = (k // foreign_ids) & 0xFFFF
            data = bytes([index & 0xFF, 0x10, counter & 0xFF, counter >> 8, 0, 0, 0x55, 0xAA])
            timeline.frames.append((k / foreign_per_s, FOREIGN_BASE_ID + index, data))
    timeline.frames.sort(key=lambda entry: entry[0])
    for offset, can_id, data in timeline.frames:
        yield CanFrame(t0 + offset, can_id, data, channel="can0")


class _Timeline:
    """The session's frames by their offset from its start (those inside it only)."""

    def __init__(self, seconds: float) -> None:
        self.seconds = seconds
        self.frames: list[tuple[float, int, bytes]] = []

    def at(self, offset: float, can_id: int, data: bytes) -> None:
        if 0.0 <= offset < self.seconds:
            self.frames.append((offset, can_id, data))


def _ground_station(timeline: _Timeline, pan_hz: float) -> None:
    """Every 10 s: the camera script, a pan at ``pan_hz`` for 5 s, two waypoint texts."""
    at = timeline.at
    cycles = int(timeline.seconds // 10) + 1
    for cycle in range(cycles):
        base = cycle * 10.0
        for offset, name, params in CAMERA_SCRIPT:
            at(base + offset, CONTROL_ID, encode_command(name, **params))
        steps = int(5.0 * pan_hz)
        for i in range(steps):
            speed = round(-5.0 + 10.0 * i / max(steps - 1, 1), 2)
            data = encode_command("gimbal_control", pan_speed_dps=speed, tilt_speed_dps=0.0)
            at(base + i / pan_hz, CONTROL_ID, data)
        for offset in (0.5, 5.5):
            for j, (can_id, data) in enumerate(encode_text(f"waypoint {cycle * 2 + 1}")):
                at(base + offset + j * 0.001, can_id, data)


def _gimbal(timeline: _Timeline) -> None:
    """Attitude feedback every 0.5 s, laser ranging every 2 s, each in four segments."""
    at = timeline.at
    for k in range(int(timeline.seconds * 2) + 1):
        t = k * 0.5 + 0.25
        pitch, yaw, motor = _pose(t)
        message = encode_attitude(pitch_deg=pitch, yaw_deg=yaw, motor_yaw_deg=motor)
        for j, segment in enumerate(segments(message)):
            at(t + j * 0.001, FEEDBACK_ID, segment)
        if k % 4 == 1:
            message = encode_ranging(
                distance_m=850.5, height_m=120.0, latitude_deg=31.1290, longitude_deg=118.1301
            )
            for j, segment in enumerate(segments(message)):
                at(t + 0.1 + j * 0.001, FEEDBACK_ID, segment)


def _uav(timeline: _Timeline, uav_hz: float) -> None:
    """GPS, altitude and attitude at ``uav_hz``."""
    at = timeline.at
    for k in range(int(timeline.seconds * uav_hz) + 1):
        t = k / uav_hz + 0.01
        at(t, GPS_ID, encode_gps(31.1234567 + t * 1e-6, 118.1234567 + t * 2e-6))
        at(t + 0.002, ALTITUDE_ID, encode_altitude(506.78 + 0.1 * math.sin(t)))
        at(t + 0.004, UAV_ATTITUDE_ID, encode_uav_attitude(1.5, -0.75, (90.0 + t) % 180))
