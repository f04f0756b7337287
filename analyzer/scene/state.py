"""What the scene and the overlays draw, followed from decoded events (no IO, no clock)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from analyzer.protocol.types import (
    TOPIC_COMMAND,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_GIMBAL_RANGING,
    TOPIC_UAV_ALTITUDE,
    TOPIC_UAV_ATTITUDE,
    TOPIC_UAV_GPS,
    Event,
)
from analyzer.scene.geometry import east_north

IMAGE_MAX = 8191  # the document's picture coordinates: 0,0 top left, 8191,8191 bottom right
TAP_SHOWN_S = 2.0  # how long the point of a tap_zoom / tap_focus stays on the picture
# Zoom commands whose ratio afterwards is known (a factor of the ratio before, or a ratio).
_ZOOM_FACTORS = {"zoom_in_2x": 2.0, "zoom_out_2x": 0.5}
_ZOOM_UNKNOWN = frozenset({"zoom_in", "zoom_out"})  # continuous: the ratio reached is not said

# What an event changed, for the views to know what to publish.
FEEDBACK = "feedback"
COMMAND = "command"
AIRCRAFT = "aircraft"
RANGING = "ranging"

# Topics that change the state; everything else is ignored.
INPUT_TOPICS = frozenset(
    {
        TOPIC_COMMAND,
        TOPIC_GIMBAL_ATTITUDE,
        TOPIC_GIMBAL_RANGING,
        TOPIC_UAV_ALTITUDE,
        TOPIC_UAV_ATTITUDE,
        TOPIC_UAV_GPS,
    }
)
# The commands that change what is drawn (``GimbalState._command``); any other command
# changes nothing, and the views skip it without a look (most are gimbal_control).
SCENE_COMMANDS = frozenset(
    {"tracking", "tracking_stop", "tap_zoom", "tap_focus", "zoom_1x", "zoom", "specified_angle"}
)


@dataclass(frozen=True, slots=True)
class Box:
    """The tracking box as the ``tracking`` command gives it, in 0..8191 picture units."""

    x: int
    y: int
    width: int
    height: int


@dataclass(frozen=True, slots=True)
class Tap:
    """The point of a ``tap_zoom`` / ``tap_focus``: ``u``, ``v`` are 0..1 of the picture."""

    time: float
    name: str
    u: float
    v: float


def _number(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    number = float(value)
    return number if math.isfinite(number) else None


def _unit(value: Any, scale: float, offset: float = 0.0) -> float | None:
    number = _number(value)
    return None if number is None else min(1.0, max(0.0, offset + number / scale))


@dataclass
class GimbalState:
    """The gimbal's last feedback, the zoom ratio and tracking box the commands set, the taps
    still shown, the last ranging and the aircraft's pose (east/north metres from its first
    fix, up from its first altitude), each updated by ``observe``."""

    pitch_deg: float | None = None
    yaw_deg: float | None = None
    motor_yaw_deg: float | None = None
    tracking: bool = False
    zoom: float | None = None  # None: not known (nothing set it, or a continuous zoom)
    box: Box | None = None
    taps: list[Tap] = field(default_factory=list)
    range_m: float | None = None
    aircraft: tuple[float, float, float] | None = None  # heading, pitch, roll (degrees)
    origin: tuple[float, float] | None = None  # latitude, longitude of the first fix
    origin_altitude_m: float | None = None  # the first altitude that came
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    altitude_m: float | None = None

    def observe(self, event: Event) -> str:
        """Take one event; says what it changed (FEEDBACK, COMMAND, AIRCRAFT, RANGING or '')."""
        topic, f = event.topic, event.fields
        if topic == TOPIC_GIMBAL_ATTITUDE:
            self.pitch_deg = _number(f.get("pitch_deg"))
            self.yaw_deg = _number(f.get("yaw_deg"))
            self.motor_yaw_deg = _number(f.get("motor_yaw_deg"))
            tracking = f.get("tracking") is True
            if self.tracking and not tracking:
                self.box = None  # the gimbal says tracking went off
            self.tracking = tracking
            self.taps = [t for t in self.taps if event.time - t.time < TAP_SHOWN_S]
            return FEEDBACK
        if topic == TOPIC_COMMAND:
            return COMMAND if f.get("name") in SCENE_COMMANDS and self._command(event) else ""
        if topic == TOPIC_GIMBAL_RANGING:
            distance = _number(f.get("distance_m"))
            ok = f.get("success") is not False and distance is not None and distance > 0
            self.range_m = distance if ok else None
            return RANGING
        if topic == TOPIC_UAV_ATTITUDE:
            heading, pitch = _number(f.get("yaw_deg")), _number(f.get("pitch_deg"))
            roll = _number(f.get("roll_deg"))
            if heading is None or pitch is None or roll is None:
                return ""
            self.aircraft = (heading, pitch, roll)
            return AIRCRAFT
        if topic == TOPIC_UAV_ALTITUDE:
            self.altitude_m = _number(f.get("altitude_m"))
            if self.origin_altitude_m is None:
                self.origin_altitude_m = self.altitude_m
            return ""
        if topic == TOPIC_UAV_GPS:
            return AIRCRAFT if self._fix(f) else ""
        return ""

    def _fix(self, f: dict[str, Any]) -> bool:
        lat, lon = _number(f.get("latitude_deg")), _number(f.get("longitude_deg"))
        if lat is None or lon is None or not (-90 <= lat <= 90 and -180 <= lon <= 180):
            return False
        if lat == 0 and lon == 0:  # what a source sends before it has a fix
            return False
        if self.origin is None:
            self.origin = (lat, lon)
        east, north = east_north(self.origin[0], self.origin[1], lat, lon)
        up = 0.0
        if self.altitude_m is not None and self.origin_altitude_m is not None:
            up = self.altitude_m - self.origin_altitude_m
        self.position = (east, north, up)
        return True

    def _command(self, event: Event) -> bool:
        f = event.fields
        name = f.get("name")
        if name == "tracking":
            x, y = _number(f.get("x")), _number(f.get("y"))
            w, h = _number(f.get("width")), _number(f.get("height"))
            if x is None or y is None or w is None or h is None:
                return False
            self.box = Box(int(x), int(y), int(w), int(h))
        elif name == "tracking_stop":
            self.box = None
        elif name == "tap_zoom":
            u, v = _unit(f.get("x_pct"), 200.0, 0.5), _unit(f.get("y_pct"), 200.0, 0.5)
            if u is None or v is None:
                return False
            self.taps.append(Tap(event.time, "tap_zoom", u, v))
            self.zoom = None if self.zoom is None else self.zoom * 2.0
        elif name == "tap_focus":
            u, v = _unit(f.get("x"), IMAGE_MAX), _unit(f.get("y"), IMAGE_MAX)
            if u is None or v is None:
                return False
            self.taps.append(Tap(event.time, "tap_focus", u, v))
        elif name == "zoom_1x":
            self.zoom = 1.0
        elif name == "zoom":
            action = f.get("action")
            if action == "zoom_1x":
                self.zoom = 1.0
            elif action in _ZOOM_FACTORS:
                ratio = None if self.zoom is None else self.zoom * _ZOOM_FACTORS[action]
                self.zoom = None if ratio is None else max(1.0, ratio)
            elif action in _ZOOM_UNKNOWN:
                self.zoom = None
            else:
                return False
        elif name == "specified_angle" and f.get("axis") == "zoom":
            ratio = _number(f.get("zoom"))
            if ratio is None or ratio <= 0:
                return False
            self.zoom = ratio
        else:
            return False
        return True

    def text(self) -> str:
        """The line drawn on the picture: 'P -45.0  Y 90.0  Z 2.0x' (? for what is unknown)."""

        def angle(value: float | None) -> str:
            return "?" if value is None else f"{value:.1f}"

        zoom = "?" if self.zoom is None else f"{self.zoom:.1f}x"
        return f"P {angle(self.pitch_deg)}  Y {angle(self.yaw_deg)}  Z {zoom}"
