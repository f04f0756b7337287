"""ArduPilot's singletons and global functions a mount driver calls, on an emulated Vehicle."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from analyzer.ardupilot.binding import Binding, CallLog, global_call, method
from analyzer.ardupilot.plan import MountStep, offset_from
from analyzer.ardupilot.userdata import (
    ABOVE_HOME,
    BUFFER_MAX,
    CameraStateUD,
    CANFrame,
    Location,
    ScriptingCANBuffer,
)
from analyzer.ardupilot.values import ScriptError, UInt32, coerce_uint32, to_integer, to_number
from analyzer.ardupilot.vehicle import Vehicle
from analyzer.protocol.ardupilot_fields import TARGET_ANGLE, TARGET_LOCATION, TARGET_RATE

MAV_SEVERITY_MAX = 7
GCS_TEXT_MAX = 50  # a STATUSTEXT carries 50 characters


class CANSingleton(Binding):
    lua_class = "CAN"

    def __init__(self, vehicle: Vehicle) -> None:
        self.vehicle = vehicle

    def _device(self, driver: int, buffer_len: Any) -> ScriptingCANBuffer | None:
        size = coerce_uint32(buffer_len, "CAN:get_device")
        if not 1 <= size <= BUFFER_MAX:
            raise ScriptError(f"CAN:get_device: buffer_len {size} out of range (1 to 25)")
        return self.vehicle.can_device(driver, size)

    @method("buffer_len", dot_ok=True)
    def get_device(self, buffer_len: Any) -> ScriptingCANBuffer | None:
        return self._device(1, buffer_len)

    @method("buffer_len", dot_ok=True)
    def get_device2(self, buffer_len: Any) -> ScriptingCANBuffer | None:
        return self._device(2, buffer_len)


class MountSingleton(Binding):
    """AP_Mount with a scripting backend: the targets of the plan, the attitude reported."""

    lua_class = "mount"

    def __init__(self, vehicle: Vehicle) -> None:
        self.vehicle = vehicle

    def _step(self, instance: Any, kind: str) -> MountStep | None:
        if to_integer(instance, "mount") != 0:
            return None  # one mount: MNT1
        step = self.vehicle.library.target
        return step if step.target == kind else None

    @method("instance")
    def get_rate_target(self, instance: Any) -> tuple[float, float, float, bool] | None:
        step = self._step(instance, TARGET_RATE)
        if step is None:
            return None
        return step.roll, step.pitch, step.yaw, step.yaw_is_earth_frame

    @method("instance")
    def get_angle_target(self, instance: Any) -> tuple[float, float, float, bool] | None:
        step = self._step(instance, TARGET_ANGLE)
        if step is None:
            return None
        return step.roll, step.pitch, step.yaw, step.yaw_is_earth_frame

    @method("instance")
    def get_location_target(self, instance: Any) -> Location | None:
        step = self._step(instance, TARGET_LOCATION)
        if step is None:
            return None
        path = self.vehicle.path
        lat, lon = offset_from((path.home_latitude_deg, path.home_longitude_deg),
                               step.north_m, step.east_m)  # fmt: skip
        here = self.vehicle.location_of(lat, lon, 0.0)
        here.frame = ABOVE_HOME
        here.alt(round(step.up_m * 100))
        return here

    @method("instance", "roll_deg", "pitch_deg", "yaw_deg")
    def set_attitude_euler(self, instance: Any, roll: Any, pitch: Any, yaw: Any) -> None:
        values = [to_number(v, "mount:set_attitude_euler") for v in (roll, pitch, yaw)]
        self.vehicle.report_attitude(to_integer(instance, "mount"), *values)


class CameraSingleton(Binding):
    lua_class = "camera"

    def __init__(self, vehicle: Vehicle) -> None:
        self.vehicle = vehicle

    @method("instance")
    def get_state(self, instance: Any) -> CameraStateUD | None:
        if to_integer(instance, "camera:get_state") != 0:
            return None
        return CameraStateUD(self.vehicle.library.camera)


class AhrsSingleton(Binding):
    lua_class = "ahrs"

    def __init__(self, vehicle: Vehicle) -> None:
        self.vehicle = vehicle

    @method()
    def get_roll_rad(self) -> float:
        return self.vehicle.attitude_rad()[0]

    @method()
    def get_pitch_rad(self) -> float:
        return self.vehicle.attitude_rad()[1]

    @method()
    def get_yaw_rad(self) -> float:
        return self.vehicle.attitude_rad()[2]

    @method(deprecated="Use get_roll_rad")
    def get_roll(self) -> float:
        return self.vehicle.attitude_rad()[0]

    @method(deprecated="Use get_pitch_rad")
    def get_pitch(self) -> float:
        return self.vehicle.attitude_rad()[1]

    @method(deprecated="Use get_yaw_rad")
    def get_yaw(self) -> float:
        return self.vehicle.attitude_rad()[2]

    @method()
    def get_location(self) -> Location:
        return self.vehicle.location()

    @method()
    def get_home(self) -> Location:
        return self.vehicle.home()

    @method()
    def get_relative_position_D_home(self) -> float:
        pose, _, _ = self.vehicle.pose()
        return -pose.altitude_m


class GpsSingleton(Binding):
    lua_class = "gps"
    lua_constants = {  # noqa: RUF012 - the enum AP_GPS gives scripts
        "NO_GPS": 0,
        "NO_FIX": 1,
        "GPS_OK_FIX_2D": 2,
        "GPS_OK_FIX_3D": 3,
        "GPS_OK_FIX_3D_DGPS": 4,
        "GPS_OK_FIX_3D_RTK_FLOAT": 5,
        "GPS_OK_FIX_3D_RTK_FIXED": 6,
    }

    def __init__(self, vehicle: Vehicle) -> None:
        self.vehicle = vehicle

    def _instance(self, instance: Any) -> None:
        if to_integer(instance, "gps") != 0:
            raise ScriptError("gps: instance out of range (one GPS)")

    @method()
    def num_sensors(self) -> int:
        return 1

    @method()
    def primary_sensor(self) -> int:
        return 0

    @method("instance")
    def status(self, instance: Any) -> int:
        self._instance(instance)
        return self.vehicle.gps_fix

    @method("instance")
    def location(self, instance: Any) -> Location:
        self._instance(instance)
        return self.vehicle.location()


class ParamSingleton(Binding):
    lua_class = "param"

    def __init__(self, vehicle: Vehicle) -> None:
        self.vehicle = vehicle

    @method("table_key", "prefix", "num_params")
    def add_table(self, table_key: Any, prefix: Any, num_params: Any) -> bool:
        from analyzer.ardupilot.vehicle import ParamTable

        key, size = to_integer(table_key, "add_table"), to_integer(num_params, "add_table")
        if not 0 <= key <= 200 or not 1 <= size <= 63 or not isinstance(prefix, str):
            raise ScriptError("param:add_table: table_key 0..200, prefix, num_params 1..63")
        if key in self.vehicle.tables:
            return False
        self.vehicle.tables[key] = ParamTable(key, prefix, size)
        return True

    @method("table_key", "param_num", "name", "default_value")
    def add_param(self, table_key: Any, param_num: Any, name: Any, default_value: Any) -> bool:
        table = self.vehicle.tables.get(to_integer(table_key, "add_param"))
        number = to_integer(param_num, "add_param")
        if table is None or not 1 <= number <= table.size or not isinstance(name, str):
            return False
        full = table.prefix + name
        if len(full) > 16:
            raise ScriptError(f"param:add_param: {full} is longer than 16 characters")
        table.names[number] = full
        self.vehicle.parameters.setdefault(full, to_number(default_value, "add_param"))
        return True

    @method("name")
    def get(self, name: Any) -> float | None:
        value = self.vehicle.parameters.get(str(name))
        return None if value is None else float(value)

    @method("name", "value")
    def set(self, name: Any, value: Any) -> bool:
        if str(name) not in self.vehicle.parameters:
            return False
        self.vehicle.parameters[str(name)] = to_number(value, "param:set")
        return True


class ParamBinding(Binding):
    """Parameter(name): a parameter bound by name (an error if there is none)."""

    lua_class = "Parameter_ud"

    def __init__(self, vehicle: Vehicle, name: str | None = None) -> None:
        self.vehicle = vehicle
        self.name = name

    @method("name")
    def init(self, name: Any) -> bool:
        if str(name) not in self.vehicle.parameters:
            return False
        self.name = str(name)
        return True

    @method()
    def get(self) -> float | None:
        if self.name is None:
            return None
        return float(self.vehicle.parameters[self.name])

    @method("value")
    def set(self, value: Any) -> bool:
        if self.name is None:
            return False
        self.vehicle.parameters[self.name] = to_number(value, "Parameter:set")
        return True


class GcsSingleton(Binding):
    lua_class = "gcs"

    def __init__(self, vehicle: Vehicle) -> None:
        self.vehicle = vehicle

    @method("severity", "text")
    def send_text(self, severity: Any, text: Any) -> None:
        level = to_integer(severity, "gcs:send_text")
        if not 0 <= level <= MAV_SEVERITY_MAX:
            raise ScriptError(f"gcs:send_text: severity {level} out of range (0 to 7)")
        self.vehicle.send_text(level, str(text)[:GCS_TEXT_MAX])


def lua_globals(vehicle: Vehicle, log: CallLog) -> dict[str, Any]:
    """Every name the emulation gives a script: singletons and global functions."""

    def millis() -> UInt32:
        return UInt32(vehicle.now_ms)

    def micros() -> UInt32:
        return UInt32(vehicle.now_ms * 1000)

    def uint32_t(value: Any = 0) -> UInt32:
        return UInt32(coerce_uint32(value, "uint32_t"))

    def new_frame() -> CANFrame:
        return CANFrame()

    def new_parameter(name: Any = None) -> ParamBinding:
        if name is None:
            return ParamBinding(vehicle)
        if str(name) not in vehicle.parameters:
            raise ScriptError(f"Parameter: no parameter named {name}")
        return ParamBinding(vehicle, str(name))

    def new_location() -> Location:
        return Location(home_cm=round(vehicle.home().alt() or 0))

    def lua_print(text: Any) -> None:
        vehicle.send_text(MAV_SEVERITY_MAX, str(text)[:GCS_TEXT_MAX])

    functions: dict[str, tuple[Callable[..., Any], tuple[str, ...]]] = {
        "millis": (millis, ()),
        "micros": (micros, ()),
        "uint32_t": (uint32_t, ("value",)),
        "CANFrame": (new_frame, ()),
        "Parameter": (new_parameter, ("name",)),
        "Location": (new_location, ()),
        "print": (lua_print, ("text",)),
    }
    out: dict[str, Any] = {}
    for name, (fn, params) in functions.items():
        optional = 1 if name in ("uint32_t", "Parameter") else 0
        fn.lua_signature = _signature(params, optional)  # type: ignore[attr-defined]
        out[name] = global_call(name, fn, log)
    out.update(
        CAN=CANSingleton(vehicle),
        mount=MountSingleton(vehicle),
        camera=CameraSingleton(vehicle),
        ahrs=AhrsSingleton(vehicle),
        gps=GpsSingleton(vehicle),
        param=ParamSingleton(vehicle),
        gcs=GcsSingleton(vehicle),
    )
    return out


def _signature(params: tuple[str, ...], optional: int) -> Any:
    from analyzer.ardupilot.binding import Signature

    return Signature(params, optional)


BINDING_CLASSES: tuple[type[Binding], ...] = (
    CANSingleton,
    MountSingleton,
    CameraSingleton,
    AhrsSingleton,
    GpsSingleton,
    ParamSingleton,
    GcsSingleton,
    ParamBinding,
)
