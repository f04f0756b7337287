"""What ArduPilot's mount and camera libraries ask of a driver, over time: a scripted plan."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

from analyzer.ardupilot.userdata import CameraState
from analyzer.protocol.ardupilot_fields import (
    CAMERA_ACTIONS,
    TARGET_ANGLE,
    TARGET_CAMERA,
    TARGET_KINDS,
    TARGET_LOCATION,
    TARGET_NONE,
    TARGET_RATE,
)

EPSILON = 1e-6


@dataclass(frozen=True)
class MountStep:
    """From ``at`` seconds on the mount library asks for this (until the next step).

    rate: ``pitch`` / ``yaw`` in deg/s; angle: in degrees, yaw from north when
    ``yaw_is_earth_frame``; location: a point ``north_m`` / ``east_m`` from home,
    ``up_m`` above it."""

    at: float
    target: str
    pitch: float = 0.0
    yaw: float = 0.0
    roll: float = 0.0
    yaw_is_earth_frame: bool = False
    north_m: float = 0.0
    east_m: float = 0.0
    up_m: float = 0.0

    def __post_init__(self) -> None:
        if self.target not in TARGET_KINDS or self.target == TARGET_CAMERA:
            raise ValueError(f"mount target {self.target!r}")


@dataclass(frozen=True)
class CameraStep:
    """At ``at`` seconds the camera library is asked for ``action`` (see CAMERA_ACTIONS):
    ``value`` is a zoom / focus rate (-1, 0, 1) or a zoom percentage; ``x``, ``y`` (and
    ``x2``, ``y2`` of a rectangle) a tracking point, 0..1 from the image's top left."""

    at: float
    action: str
    value: float = 0.0
    x: float = 0.0
    y: float = 0.0
    x2: float = 0.0
    y2: float = 0.0

    def __post_init__(self) -> None:
        if self.action not in CAMERA_ACTIONS:
            raise ValueError(f"camera action {self.action!r}")

    def apply(self, state: CameraState) -> CameraState:
        """The camera state after this action."""
        a = self.action
        if a == "take_picture":
            return replace(state, take_pic_incr=(state.take_pic_incr + 1) & 0xFFFF)
        if a in ("record_start", "record_stop"):
            return replace(state, recording_video=a == "record_start")
        if a == "zoom_rate":
            return replace(state, zoom_type=1, zoom_value=self.value)
        if a == "zoom_percent":
            return replace(state, zoom_type=2, zoom_value=self.value)
        if a == "focus_rate":
            return replace(state, focus_type=1, focus_value=self.value)
        if a == "focus_auto":
            return replace(state, focus_type=4, focus_value=0.0)
        if a == "track_point":
            return replace(state, tracking_type=1, tracking_p1=(self.x, self.y))
        if a == "track_rectangle":
            return replace(
                state, tracking_type=2, tracking_p1=(self.x, self.y), tracking_p2=(self.x2, self.y2)
            )
        return replace(state, tracking_type=0)  # track_stop


Step = MountStep | CameraStep

# The demo's plan: a pilot's rate targets, angle targets in both frames, a point to look
# at, and the camera; it starts over every DEMO_PERIOD seconds.
DEMO_PLAN: tuple[Step, ...] = (
    MountStep(0.5, TARGET_RATE, pitch=-20.0),
    MountStep(2.0, TARGET_NONE),
    MountStep(2.4, TARGET_RATE, yaw=25.0),
    MountStep(3.6, TARGET_RATE),  # the stick back in the middle: rates of 0
    MountStep(4.0, TARGET_ANGLE, pitch=-30.0, yaw=45.0),
    MountStep(7.0, TARGET_ANGLE, pitch=-45.0, yaw=120.0, yaw_is_earth_frame=True),
    CameraStep(7.5, "take_picture"),
    CameraStep(8.0, "zoom_rate", value=1.0),
    CameraStep(9.0, "zoom_rate", value=0.0),
    CameraStep(9.5, "record_start"),
    MountStep(10.0, TARGET_LOCATION, north_m=-100.0, east_m=60.0),
    CameraStep(13.0, "track_point", x=0.6, y=0.45),
    CameraStep(15.0, "track_stop"),
    CameraStep(15.5, "zoom_percent", value=0.0),
    CameraStep(16.0, "focus_auto"),
    MountStep(17.0, TARGET_ANGLE),
    CameraStep(18.5, "record_stop"),
)
DEMO_PERIOD = 20.0


class MountLibrary:
    """The plan played against a clock (sans-IO): ``advance(t)`` returns the steps that
    came due since the last call; ``target`` and ``camera`` are what is asked now."""

    def __init__(self, plan: tuple[Step, ...] = DEMO_PLAN, period: float | None = DEMO_PERIOD):
        self.plan = tuple(sorted(plan, key=lambda s: s.at))
        self.period = period
        self.target = MountStep(0.0, TARGET_NONE)
        self.camera = CameraState()
        self._round = 0
        self._index = 0

    def advance(self, t: float) -> list[Step]:
        due: list[Step] = []
        while self.plan:
            if self._index >= len(self.plan):
                if not self.period:
                    break
                self._round += 1
                self._index = 0
                continue
            step = self.plan[self._index]
            if self._round * (self.period or 0.0) + step.at > t + EPSILON:
                break
            if isinstance(step, MountStep):
                self.target = step
            else:
                self.camera = step.apply(self.camera)
            due.append(step)
            self._index += 1
        return due


def step_fields(step: Step, home: tuple[float, float]) -> dict[str, Any]:
    """The /ardupilot/targets fields of a step (``home``: latitude, longitude)."""
    if isinstance(step, CameraStep):
        out: dict[str, Any] = {"target": TARGET_CAMERA, "camera_action": step.action}
        if step.action in ("zoom_rate", "zoom_percent", "focus_rate"):
            out["value"] = step.value
        if step.action in ("track_point", "track_rectangle"):
            out.update(x=step.x, y=step.y)
        if step.action == "track_rectangle":
            out.update(x2=step.x2, y2=step.y2)
        return out
    out = {"target": step.target}
    if step.target == TARGET_RATE:
        out.update(roll_dps=step.roll, pitch_dps=step.pitch, yaw_dps=step.yaw)
        out["yaw_is_earth_frame"] = step.yaw_is_earth_frame
    elif step.target == TARGET_ANGLE:
        out.update(roll_deg=step.roll, pitch_deg=step.pitch, yaw_deg=step.yaw)
        out["yaw_is_earth_frame"] = step.yaw_is_earth_frame
    elif step.target == TARGET_LOCATION:
        lat, lon = offset_from(home, step.north_m, step.east_m)
        out.update(latitude_deg=lat, longitude_deg=lon, altitude_m=step.up_m)
    return out


def offset_from(home: tuple[float, float], north_m: float, east_m: float) -> tuple[float, float]:
    """A position ``north_m`` / ``east_m`` from ``home``, as ArduPilot's Location:offset does."""
    lat, lon = home
    dlat = north_m / 111_318.84502145034
    dlon = east_m / (111_318.84502145034 * max(0.01, math.cos(math.radians(lat))))
    return lat + dlat, lon + dlon
