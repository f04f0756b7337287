"""Plays the UAV: GPS, altitude, attitude and text status frames along a circular flight path."""

from __future__ import annotations

import math
from dataclasses import dataclass

from analyzer.protocol.ids import ALTITUDE_ID, GPS_ID, UAV_ATTITUDE_ID
from analyzer.protocol.uav import encode_altitude, encode_gps, encode_text, encode_uav_attitude
from analyzer.sim.model import UavPose, offset_position, wrap180

GRAVITY = 9.81

# can_id -> period in seconds
PERIODS: dict[int, float] = {GPS_ID: 0.2, ALTITUDE_ID: 0.2, UAV_ATTITUDE_ID: 0.1}
TEXT_PERIOD = 5.0
TEXTS = (
    "UAV armed",
    "Takeoff",
    "Mission: orbit 150 m",
    "Battery 16.4V 92%",
    "GPS 3D fix, 14 sats",
    "Wind 4 m/s from NW",
    "Waypoint reached",
)


@dataclass(frozen=True)
class FlightPath:
    """Climb to a cruise altitude while orbiting a home point clockwise (seen from above)."""

    home_latitude_deg: float = 31.1234567  # the document's GPS example
    home_longitude_deg: float = 118.1234567
    radius_m: float = 150.0
    speed_mps: float = 12.0
    cruise_altitude_m: float = 120.0
    climb_mps: float = 6.0
    heading_deg: float | None = None  # the nose held this way (a multicopter can); None: ahead

    def pose(self, t: float) -> tuple[UavPose, float, float]:
        """Position at ``t`` seconds after takeoff -> (pose, pitch_deg, roll_deg)."""
        t = max(0.0, t)
        angle = self.speed_mps * t / self.radius_m  # radians around the home point
        north, east = self.radius_m * math.cos(angle), self.radius_m * math.sin(angle)
        lat, lon = offset_position(self.home_latitude_deg, self.home_longitude_deg, north, east)
        altitude = min(self.cruise_altitude_m, self.climb_mps * t)
        climbing = altitude < self.cruise_altitude_m
        heading = wrap180(math.degrees(angle) + 90.0)  # tangent of the orbit
        if self.heading_deg is not None:
            heading = wrap180(self.heading_deg)
        pitch = math.degrees(math.atan2(self.climb_mps, self.speed_mps)) if climbing else 0.0
        roll = math.degrees(math.atan(self.speed_mps**2 / (GRAVITY * self.radius_m)))
        return UavPose(lat, lon, altitude, heading), pitch, roll


class UavPlayer:
    """Which UAV status frames are due at a time; sans-IO (``due(now)`` returns CAN frames)."""

    def __init__(self, start: float, path: FlightPath | None = None) -> None:
        self.start = start
        self.path = path or FlightPath()
        self._next = dict.fromkeys(PERIODS, start)
        self._next_text = start
        self._text_index = 0

    def pose(self, now: float) -> UavPose:
        return self.path.pose(now - self.start)[0]

    def next_time(self) -> float:
        return min(self._next_text, *self._next.values())

    def due(self, now: float) -> list[tuple[int, bytes]]:
        out: list[tuple[int, bytes]] = []
        pose, pitch, roll = self.path.pose(now - self.start)
        for can_id, period in PERIODS.items():
            if now < self._next[can_id]:
                continue
            self._next[can_id] = max(self._next[can_id] + period, now - period)
            if can_id == GPS_ID:
                out.append((can_id, encode_gps(pose.latitude_deg, pose.longitude_deg)))
            elif can_id == ALTITUDE_ID:
                out.append((can_id, encode_altitude(pose.altitude_m)))
            else:
                out.append((can_id, encode_uav_attitude(pitch, roll, pose.heading_deg)))
        if now >= self._next_text:
            self._next_text = max(self._next_text + TEXT_PERIOD, now)
            out.extend(encode_text(TEXTS[self._text_index % len(TEXTS)]))
            self._text_index += 1
        return out
