"""ArduPilot's userdata a mount driver meets: CANFrame, the CAN buffer, Location, vectors."""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from analyzer.ardupilot.binding import Binding, method
from analyzer.ardupilot.values import (
    INT32_MAX,
    ScriptError,
    UInt32,
    coerce_uint32,
    int32,
    to_integer,
    to_number,
)

# AP_HAL::CANFrame's flags in its id (libraries/AP_HAL/CANIface.h)
FLAG_EFF = 1 << 31  # extended (29-bit) frame
FLAG_RTR = 1 << 30  # remote transmission request
FLAG_ERR = 1 << 29  # error frame
MASK_EXT_ID = 0x1FFFFFFF
MASK_STD_ID = 0x7FF
CAN_DATA_SIZE = 8
BUFFER_MAX = 25  # CAN:get_device's buffer_len is 1 to 25
MAX_FILTERS = 8

LATLON_TO_M = 0.011131884502145034  # ArduPilot's metres per 1e-7 degree (Location.cpp)


class CANFrame(Binding):
    """AP_HAL::CANFrame: ``id`` holds the flags (bit 31 = extended), ``data`` is 0-based."""

    lua_class = "CANFrame_ud"

    def __init__(self) -> None:
        self.raw_id = 0
        self.length = 0
        self.bytes = bytearray(CAN_DATA_SIZE)

    @method("value", optional=1)
    def id(self, value: Any = None) -> UInt32 | None:
        if value is None:
            return UInt32(self.raw_id)
        self.raw_id = coerce_uint32(value, "CANFrame:id")
        return None

    @method("index", "value", optional=1)
    def data(self, index: Any, value: Any = None) -> int | None:
        i = to_integer(index, "CANFrame:data")
        if not 0 <= i < CAN_DATA_SIZE:
            raise ScriptError(f"CANFrame:data: index {i} out of range (0 to 7)")
        if value is None:
            return self.bytes[i]
        self.bytes[i] = to_integer(value, "CANFrame:data") & 0xFF  # a C cast to uint8_t
        return None

    @method("value", optional=1)
    def dlc(self, value: Any = None) -> int | None:
        if value is None:
            return self.length
        n = to_integer(value, "CANFrame:dlc")
        if not 0 <= n <= CAN_DATA_SIZE:
            raise ScriptError(f"CANFrame:dlc: {n} out of range (0 to 8)")
        self.length = n
        return None

    @method()
    def id_signed(self) -> int:
        return int32(self.raw_id & (MASK_EXT_ID if self.isExtended() else MASK_STD_ID))

    @method()
    def isExtended(self) -> bool:
        return bool(self.raw_id & FLAG_EFF)

    @method()
    def isRemoteTransmissionRequest(self) -> bool:
        return bool(self.raw_id & FLAG_RTR)

    @method()
    def isErrorFrame(self) -> bool:
        return bool(self.raw_id & FLAG_ERR)

    # -- for the bus ---------------------------------------------------------------------

    @property
    def can_id(self) -> int:
        """The identifier on the wire: 29 bits of an extended frame, 11 of a standard one."""
        return self.raw_id & (MASK_EXT_ID if self.raw_id & FLAG_EFF else MASK_STD_ID)

    @property
    def payload(self) -> bytes:
        return bytes(self.bytes[: self.length])

    @classmethod
    def received(cls, can_id: int, data: bytes, extended: bool) -> CANFrame:
        frame = cls()
        frame.raw_id = can_id | (FLAG_EFF if extended else 0)
        frame.length = len(data)
        frame.bytes[: len(data)] = data
        return frame


# (CAN ID, data, extended) -> True when the bus took the frame
Transmit = Callable[[int, bytes, bool], bool]


class ScriptingCANBuffer(Binding):
    """A scripting CAN driver's buffer: at most ``size`` received frames wait for
    read_frame (more are dropped); write_frame hands a frame to the bus."""

    lua_class = "ScriptingCANBuffer_ud"

    def __init__(self, driver: int, size: int, transmit: Transmit) -> None:
        self.driver = driver
        self.size = size
        self.transmit = transmit
        self.received: deque[CANFrame] = deque()
        self.dropped = 0
        self.filters: list[tuple[int, int]] = []
        self.timeouts_us: list[int] = []  # every write_frame timeout the script asked for

    def deliver(self, can_id: int, data: bytes, extended: bool) -> None:
        frame = CANFrame.received(can_id, data, extended)
        if self.filters and not any(frame.raw_id & m == v for m, v in self.filters):
            return
        if len(self.received) >= self.size:
            self.dropped += 1
            return
        self.received.append(frame)

    @method()
    def read_frame(self) -> CANFrame | None:
        return self.received.popleft() if self.received else None

    @method("frame", "timeout_us")
    def write_frame(self, frame: Any, timeout_us: Any) -> bool:
        if not isinstance(frame, CANFrame):
            raise ScriptError("ScriptingCANBuffer:write_frame: CANFrame expected")
        self.timeouts_us.append(coerce_uint32(timeout_us, "write_frame"))
        extended = bool(frame.raw_id & FLAG_EFF)
        return self.transmit(frame.can_id, frame.payload, extended)

    @method("mask", "value")
    def add_filter(self, mask: Any, value: Any) -> bool:
        if len(self.filters) >= MAX_FILTERS:
            return False
        m = coerce_uint32(mask, "add_filter")
        self.filters.append((m, coerce_uint32(value, "add_filter") & m))
        return True


class Vector2f(Binding):
    lua_class = "Vector2f_ud"

    def __init__(self, x: float = 0.0, y: float = 0.0) -> None:
        self._x, self._y = x, y

    @method("value", optional=1)
    def x(self, value: Any = None) -> float | None:
        if value is None:
            return self._x
        self._x = to_number(value, "Vector2f:x")
        return None

    @method("value", optional=1)
    def y(self, value: Any = None) -> float | None:
        if value is None:
            return self._y
        self._y = to_number(value, "Vector2f:y")
        return None

    @method()
    def length(self) -> float:
        return math.hypot(self._x, self._y)


class Vector3f(Vector2f):
    lua_class = "Vector3f_ud"

    def __init__(self, x: float = 0.0, y: float = 0.0, z: float = 0.0) -> None:
        super().__init__(x, y)
        self._z = z

    @method("value", optional=1)
    def z(self, value: Any = None) -> float | None:
        if value is None:
            return self._z
        self._z = to_number(value, "Vector3f:z")
        return None

    @method()
    def length(self) -> float:
        return math.sqrt(self._x**2 + self._y**2 + self._z**2)


ABSOLUTE, ABOVE_HOME = 0, 1  # Location::AltFrame


class Location(Binding):
    """Location: latitude / longitude in 1e-7 degrees, altitude in cm, absolute or above
    home (``home_cm`` is home's absolute altitude, for change_alt_frame)."""

    lua_class = "Location_ud"

    def __init__(self, lat: int = 0, lng: int = 0, alt: int = 0, frame: int = ABSOLUTE,
                 home_cm: int = 0) -> None:  # fmt: skip
        self._lat, self._lng, self._alt = lat, lng, alt
        self.frame = frame
        self.home_cm = home_cm

    def _field(self, name: str, value: Any, limit: int) -> int | None:
        if value is None:
            return int(getattr(self, "_" + name))
        number = to_integer(value, f"Location:{name}")
        if not -limit <= number <= limit:
            raise ScriptError(f"Location:{name}: {number} out of range")
        setattr(self, "_" + name, number)
        return None

    @method("value", optional=1)
    def lat(self, value: Any = None) -> int | None:
        return self._field("lat", value, 900_000_000)

    @method("value", optional=1)
    def lng(self, value: Any = None) -> int | None:
        return self._field("lng", value, 1_800_000_000)

    @method("value", optional=1)
    def alt(self, value: Any = None) -> int | None:
        return self._field("alt", value, INT32_MAX)

    @method("value", optional=1)
    def relative_alt(self, value: Any = None) -> bool | None:
        if value is None:
            return self.frame == ABOVE_HOME
        self.frame = ABOVE_HOME if value else ABSOLUTE  # the flag alone, as ArduPilot's
        return None

    @method()
    def copy(self) -> Location:
        return Location(self._lat, self._lng, self._alt, self.frame, self.home_cm)

    @method("desired_frame")
    def change_alt_frame(self, desired_frame: Any) -> bool:
        frame = to_integer(desired_frame, "Location:change_alt_frame")
        if frame not in (ABSOLUTE, ABOVE_HOME):
            return False  # above origin / terrain: not known here
        if frame != self.frame:
            self._alt += self.home_cm if frame == ABSOLUTE else -self.home_cm
            self.frame = frame
        return True

    def _ne(self, other: Location) -> tuple[float, float]:
        scale = math.cos(math.radians((self._lat + other._lat) / 2 * 1e-7))
        north = (other._lat - self._lat) * LATLON_TO_M
        east = (other._lng - self._lng) * LATLON_TO_M * scale
        return north, east

    @method("loc")
    def get_distance_NE(self, loc: Any) -> Vector2f:
        return Vector2f(*self._ne(_location(loc)))

    @method("loc")
    def get_distance_NED(self, loc: Any) -> Vector3f:
        other = _location(loc)
        return Vector3f(*self._ne(other), (self._alt - other._alt) * 0.01)

    @method("loc")
    def get_distance(self, loc: Any) -> float:
        return math.hypot(*self._ne(_location(loc)))

    @method("loc")
    def get_bearing(self, loc: Any) -> float:
        north, east = self._ne(_location(loc))
        return math.atan2(east, north) % (2 * math.pi)


def _location(value: Any) -> Location:
    if not isinstance(value, Location):
        raise ScriptError("Location expected")
    return value


@dataclass
class CameraState:
    """AP_Camera::camera_state_t: what the camera library asks of the camera."""

    take_pic_incr: int = 0
    recording_video: bool = False
    zoom_type: int = 0  # 1 rate (-1 out, 0 hold, 1 in), 2 percent (0..100)
    zoom_value: float = 0.0
    focus_type: int = 0  # 1 rate, 2 percent, 4 auto
    focus_value: float = 0.0
    tracking_type: int = 0  # 0 none, 1 point, 2 rectangle
    tracking_p1: tuple[float, float] = (0.0, 0.0)  # 0..1 from the left / top
    tracking_p2: tuple[float, float] = (0.0, 0.0)


class CameraStateUD(Binding):
    lua_class = "AP_Camera__camera_state_t_ud"

    def __init__(self, state: CameraState) -> None:
        self.state = state

    @method()
    def take_pic_incr(self) -> int:
        return self.state.take_pic_incr

    @method()
    def recording_video(self) -> bool:
        return self.state.recording_video

    @method()
    def zoom_type(self) -> int:
        return self.state.zoom_type

    @method()
    def zoom_value(self) -> float:
        return self.state.zoom_value

    @method()
    def focus_type(self) -> int:
        return self.state.focus_type

    @method()
    def focus_value(self) -> float:
        return self.state.focus_value

    @method()
    def tracking_type(self) -> int:
        return self.state.tracking_type

    @method()
    def tracking_p1(self) -> Vector2f:
        return Vector2f(*self.state.tracking_p1)

    @method()
    def tracking_p2(self) -> Vector2f:
        return Vector2f(*self.state.tracking_p2)
