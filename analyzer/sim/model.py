"""The gimbal's physical model: commands in, angles and zoom out; no IO, time is passed in."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from analyzer.protocol.feedback import ATTITUDE, MOTOR_YAW_LIMIT, WIDE_MOTOR_YAW_TYPES
from analyzer.protocol.fields import Field
from analyzer.sim.behaviour import Behaviour


def _limits(field: Field) -> tuple[float, float]:
    lo, hi = field.value_limits()
    assert lo is not None and hi is not None
    return float(lo), float(hi)


_ATTITUDE_FIELDS = {f.name: f for f in ATTITUDE.layout.fields}
PITCH_MIN, PITCH_MAX = _limits(_ATTITUDE_FIELDS["pitch_deg"])  # -110 .. 60 deg (chapter 2.2)
MOTOR_YAW_WIDE = max(_limits(_ATTITUDE_FIELDS["motor_yaw_deg"]))  # 325 deg on 3.5x models

HOLD_S = 0.3  # gimbal_control keeps turning this long after the last command
SLEW_DPS = 60.0  # speed of moves to an angle (specified_angle, look_down, forward, tap_zoom)
ZOOM_RATE = 6.0  # zoom ratio change per second (continuous zoom and moves to a ratio)
MAX_ZOOM = 30.0
# The optical zoom range of the 3.5x models (Note 1's gimbal types 3 and 4).
SHORT_ZOOM_TYPES = frozenset({3, 4})
SHORT_ZOOM = 3.5
DIGITAL_ZOOM_RATE = 4.0  # digital zoom ratio change per second
MAX_DIGITAL_ZOOM = 8.0
PIP_MODES = 4  # picture-in-picture layouts the dual-sensor camera cycles through
DEFAULT_PALETTE = "white_hot"
HFOV_1X = 60.0  # horizontal / vertical field of view at 1x, degrees
VFOV_1X = 34.0
LOOK_DOWN_DEG = -90.0

# Control modes of Note 2.
FULL_LOCK = 1  # speed controlled
LOCKING = 3  # angle controlled


def wrap180(angle: float) -> float:
    """An angle in degrees folded into [-180, 180)."""
    return (angle + 180.0) % 360.0 - 180.0


def _toward(value: float, target: float, step: float) -> float:
    if abs(target - value) <= step:
        return target
    return value + math.copysign(step, target - value)


@dataclass
class UavPose:
    """What the gimbal knows about the aircraft it hangs under."""

    latitude_deg: float = 31.1234567  # the document's GPS example
    longitude_deg: float = 118.1234567
    altitude_m: float = 100.0
    heading_deg: float = 0.0


class GimbalModel:
    """State of one gimbal, advanced by ``step(now)`` and changed by decoded commands.

    ``apply(fields, now)`` takes the fields of a /gimbal/command event (as the decoder
    produces them), so the simulator understands exactly what the analyzer decodes.
    """

    def __init__(
        self,
        now: float = 0.0,
        *,
        gimbal_type: int = 1,
        max_zoom: float | None = None,
        behaviour: Behaviour | None = None,
    ):
        self.behaviour = behaviour or Behaviour()
        self.gimbal_type = gimbal_type
        self.max_zoom = optical_zoom_range(gimbal_type) if max_zoom is None else max_zoom
        self.motor_yaw_limit = (
            MOTOR_YAW_WIDE if gimbal_type in WIDE_MOTOR_YAW_TYPES else MOTOR_YAW_LIMIT / 100
        )
        self.pitch_deg = 0.0
        self.motor_yaw_deg = 0.0
        self.zoom = 1.0
        self.tracking = False
        self.tracking_box = (0.0, 0.0)  # width, height of the tracked box (fractions of the image)
        self.digital_zoom = 1.0
        self.palette = DEFAULT_PALETTE  # the thermal image's colour palette
        self.pip_mode = 0  # the picture-in-picture layout, one of PIP_MODES
        self.control_mode = LOCKING
        self.recording = False
        self.uav = UavPose()
        self.last_action = ""  # the last command that changes nothing the feedback shows
        self.commands = 0
        self.ignored = 0
        self._time = now
        self._pan_dps = 0.0
        self._tilt_dps = 0.0
        self._speed_until = now
        self._pitch_target: float | None = None
        self._yaw_target: float | None = None  # motor yaw to reach
        self._yaw_geodetic: float | None = None  # geodetic yaw to hold while the UAV turns
        self._zoom_target: float | None = None
        self._zoom_dir = 0.0
        self._digital_dir = 0.0

    # -- what the feedback reports -----------------------------------------------------------

    @property
    def yaw_deg(self) -> float:
        """Geomagnetic yaw: the aircraft heading plus the yaw motor angle, in [0, 360)."""
        yaw = (self.uav.heading_deg + self.motor_yaw_deg) % 360.0
        return 0.0 if yaw >= 359.995 else yaw

    def attitude(self) -> dict[str, Any]:
        """Keyword arguments of ``encode_attitude`` for the current state."""
        return {
            "pitch_deg": self.pitch_deg,
            "yaw_deg": self.yaw_deg,
            "motor_yaw_deg": self.motor_yaw_deg,
            "gimbal_type": self.gimbal_type,
            "tracking": self.tracking,
            "control_mode": self.control_mode,
        }

    def ranging(self) -> dict[str, Any]:
        """Keyword arguments of ``encode_ranging``: where the line of sight meets the ground."""
        uav = self.uav
        down = -self.pitch_deg
        success = 2.0 <= down <= 178.0 and uav.altitude_m > 0
        if success:
            slant = uav.altitude_m / math.sin(math.radians(down))
            ground = uav.altitude_m / math.tan(math.radians(down))
            success = slant <= 6000.0
        if not success:
            return {
                "distance_m": 0.0,
                "height_m": 0.0,
                "latitude_deg": 0.0,
                "longitude_deg": 0.0,
                "success": False,
            }
        bearing = math.radians(self.yaw_deg)
        north, east = ground * math.cos(bearing), ground * math.sin(bearing)
        lat, lon = offset_position(uav.latitude_deg, uav.longitude_deg, north, east)
        return {
            "distance_m": slant,
            "height_m": 0.0,
            "latitude_deg": lat,
            "longitude_deg": lon,
            "success": True,
        }

    def point_at(self, pitch: float, motor_yaw: float) -> None:
        """Put the gimbal at this attitude (within its range), still: where it was left."""
        self._set_pitch(pitch)
        self._set_motor_yaw(motor_yaw)

    # -- time ----------------------------------------------------------------------------------

    def step(self, now: float) -> None:
        """Advance the state to ``now`` (earlier times are ignored)."""
        dt = now - self._time
        if dt <= 0:
            return
        moving = max(0.0, min(now, self._speed_until) - self._time)
        speed = self.behaviour.speed
        if moving > 0:
            self._set_pitch(self.pitch_deg + self._tilt_dps * speed * moving)
            self._set_motor_yaw(self.motor_yaw_deg + self._pan_dps * speed * moving)
        slew = SLEW_DPS * speed * dt
        if self._pitch_target is not None:
            self._set_pitch(_toward(self.pitch_deg, self._pitch_target, slew))
            if self.pitch_deg == self._pitch_target:
                self._pitch_target = None
        if self._yaw_geodetic is not None:
            self._yaw_target = self._clamp_yaw(wrap180(self._yaw_geodetic - self.uav.heading_deg))
        if self._yaw_target is not None:
            self._set_motor_yaw(_toward(self.motor_yaw_deg, self._yaw_target, slew))
            if self.motor_yaw_deg == self._yaw_target:
                self._yaw_target = None
        if self._zoom_target is not None:
            self.zoom = _toward(self.zoom, self._zoom_target, ZOOM_RATE * dt)
            if self.zoom == self._zoom_target:
                self._zoom_target = None
        elif self._zoom_dir:
            self.zoom = min(self.max_zoom, max(1.0, self.zoom + self._zoom_dir * ZOOM_RATE * dt))
        if self._digital_dir:
            digital = self.digital_zoom + self._digital_dir * DIGITAL_ZOOM_RATE * dt
            self.digital_zoom = min(MAX_DIGITAL_ZOOM, max(1.0, digital))
        self._time = now

    def _set_pitch(self, value: float) -> None:
        self.pitch_deg = min(PITCH_MAX, max(PITCH_MIN, value))

    def _clamp_yaw(self, value: float) -> float:
        return min(self.motor_yaw_limit, max(-self.motor_yaw_limit, value))

    def _set_motor_yaw(self, value: float) -> None:
        self.motor_yaw_deg = self._clamp_yaw(value)

    # -- commands ------------------------------------------------------------------------------

    def apply(self, fields: dict[str, Any], now: float) -> bool:
        """Act on a decoded command; False when the gimbal ignores it."""
        self.step(now)
        name = str(fields.get("name"))
        handler = _HANDLERS.get(name)
        if handler is None or name in self.behaviour.ignore:
            self.ignored += 1
            return False
        self.commands += 1
        handler(self, fields, now)
        return True

    def _turn_to(self, pitch: float | None = None, motor_yaw: float | None = None) -> None:
        self._speed_until = self._time
        self.control_mode = LOCKING
        reach = self.behaviour.reach
        if pitch is not None:
            pitch = self.pitch_deg + reach * (pitch - self.pitch_deg)
            self._pitch_target = min(PITCH_MAX, max(PITCH_MIN, pitch))
        if motor_yaw is not None:
            self._yaw_geodetic = None
            motor_yaw = self.motor_yaw_deg + reach * (motor_yaw - self.motor_yaw_deg)
            self._yaw_target = self._clamp_yaw(motor_yaw)

    def _zoom_to(self, ratio: float) -> None:
        self._zoom_dir = 0.0
        self._zoom_target = min(self.max_zoom, max(1.0, ratio))

    def _look_at(self, x_fraction: float, y_fraction: float) -> None:
        """Turn so that a point of the image (-1..1 from the centre) comes to the centre."""
        self._turn_to(
            pitch=self.pitch_deg - y_fraction * VFOV_1X / 2 / self.zoom,
            motor_yaw=self.motor_yaw_deg + x_fraction * HFOV_1X / 2 / self.zoom,
        )

    def _gimbal_control(self, f: dict[str, Any], now: float) -> None:
        way = -1.0 if self.behaviour.wrong_way else 1.0
        pan = way * float(f.get("pan_speed_dps", 0.0))
        tilt = way * float(f.get("tilt_speed_dps", 0.0))
        drift = self.behaviour.drift_s
        if pan == 0 and tilt == 0 and drift and self._speed_until > now:
            # told to stop while turning: it turns on a while (however often it is told)
            self._speed_until = min(self._speed_until, now + drift)
        else:
            self._pan_dps, self._tilt_dps = pan, tilt
            self._speed_until = now + HOLD_S + drift
        self._pitch_target = self._yaw_target = self._yaw_geodetic = None
        self.control_mode = FULL_LOCK

    def _specified_angle(self, f: dict[str, Any], now: float) -> None:
        axis = f.get("axis")
        if axis == "yaw" and "yaw_deg" in f:
            yaw = float(f["yaw_deg"])
            airframe = f.get("coordinate_system") == "airframe"
            if airframe or self.behaviour.geodetic_as_airframe:
                self._turn_to(motor_yaw=wrap180(yaw))
            else:  # geodetic: hold that heading however the aircraft turns
                self._turn_to(motor_yaw=wrap180(yaw - self.uav.heading_deg))
                now_yaw = self.uav.heading_deg + self.motor_yaw_deg
                self._yaw_geodetic = now_yaw + self.behaviour.reach * wrap180(yaw - now_yaw)
        elif axis == "pitch" and "pitch_deg" in f:
            self._turn_to(pitch=float(f["pitch_deg"]))
        elif axis == "zoom" and "zoom" in f:
            self._zoom_to(float(f["zoom"]))

    def _zoom(self, f: dict[str, Any], now: float) -> None:
        action = f.get("action")
        if action in ("zoom_in", "zoom_out"):
            self._zoom_target = None
            self._zoom_dir = 1.0 if action == "zoom_in" else -1.0
        elif action == "stop":
            self._zoom_dir = 0.0
            self._zoom_target = None
        elif action == "zoom_1x":
            self._zoom_to(1.0)
        elif action == "zoom_in_2x":
            self._zoom_to(self.zoom * 2)
        elif action == "zoom_out_2x":
            self._zoom_to(self.zoom / 2)

    def _digital_zoom(self, f: dict[str, Any], now: float) -> None:
        action = f.get("action")
        self._digital_dir = {"zoom_in": 1.0, "zoom_out": -1.0}.get(str(action), 0.0)

    def _tap_zoom(self, f: dict[str, Any], now: float) -> None:
        self._look_at(float(f.get("x_pct", 0.0)) / 100, float(f.get("y_pct", 0.0)) / 100)
        self._zoom_to(self.zoom * 2)

    def _tracking(self, f: dict[str, Any], now: float) -> None:
        centre = 8191 / 2
        self._look_at(
            (float(f.get("x", centre)) - centre) / centre,
            (float(f.get("y", centre)) - centre) / centre,
        )
        self.tracking = True
        self.tracking_box = (float(f.get("width", 0)) / 8191, float(f.get("height", 0)) / 8191)

    def _tracking_stop(self, f: dict[str, Any], now: float) -> None:
        self.tracking = False

    def _look_down(self, f: dict[str, Any], now: float) -> None:
        self._turn_to(pitch=LOOK_DOWN_DEG)

    def _forward(self, f: dict[str, Any], now: float) -> None:
        self._turn_to(pitch=0.0, motor_yaw=0.0)

    def _zoom_1x(self, f: dict[str, Any], now: float) -> None:
        self._zoom_to(1.0)

    def _recording(self, f: dict[str, Any], now: float) -> None:
        self.recording = f.get("action") == "start"
        self.last_action = f"recording {f.get('action')}"

    def _palette(self, f: dict[str, Any], now: float) -> None:
        self.palette = str(f.get("palette", self.palette))
        self._other(f, now)

    def _pip_cycle(self, f: dict[str, Any], now: float) -> None:
        self.pip_mode = (self.pip_mode + 1) % PIP_MODES
        self._other(f, now)

    def _other(self, f: dict[str, Any], now: float) -> None:
        details = [str(v) for k, v in f.items() if k in _ACTION_KEYS]
        self.last_action = " ".join([str(f.get("name")), *details])


_ACTION_KEYS = ("action", "mode", "palette", "shots", "delay_s", "timer_s")

_HANDLERS = {
    "gimbal_control": GimbalModel._gimbal_control,
    "specified_angle": GimbalModel._specified_angle,
    "zoom": GimbalModel._zoom,
    "digital_zoom": GimbalModel._digital_zoom,
    "tap_zoom": GimbalModel._tap_zoom,
    "tracking": GimbalModel._tracking,
    "tracking_stop": GimbalModel._tracking_stop,
    "look_down": GimbalModel._look_down,
    "forward": GimbalModel._forward,
    "quick_calibration": GimbalModel._forward,
    "zoom_1x": GimbalModel._zoom_1x,
    "recording": GimbalModel._recording,
    "snapshot": GimbalModel._other,
    "focus": GimbalModel._other,
    "tap_focus": GimbalModel._other,
    "palette": GimbalModel._palette,
    "pip_cycle": GimbalModel._pip_cycle,
}


def optical_zoom_range(gimbal_type: int) -> float:
    """The largest optical zoom ratio of a gimbal type of Note 1."""
    return SHORT_ZOOM if gimbal_type in SHORT_ZOOM_TYPES else MAX_ZOOM


EARTH_M_PER_DEG = 111_320.0


def offset_position(lat: float, lon: float, north_m: float, east_m: float) -> tuple[float, float]:
    """A position moved by metres north / east (flat-earth approximation, fine for a demo)."""
    dlat = north_m / EARTH_M_PER_DEG
    dlon = east_m / (EARTH_M_PER_DEG * max(0.01, math.cos(math.radians(lat))))
    return lat + dlat, lon + dlon
