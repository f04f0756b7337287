"""The driver's own functions on Lua built as ArduPilot builds it (32-bit integers and
floats) give the Python encoder's bytes: the CRC, every command and status frame the driver
sends, the feedback it parses, the angles to a location target; and its timers keep their
schedule across millis()'s wraps at 2^31 and 2^32.

A number reaches the driver as ArduPilot's bindings give it, a 32-bit float: the Python
side is handed the same float32 value, and where the driver computes in floats first
(tracking boxes, zoom ratios, angles) numpy's float32 follows the same IEEE steps.
"""

from __future__ import annotations

import math
import random
from collections.abc import Iterator
from types import ModuleType
from typing import Any

import numpy as np
import pytest

from analyzer.ardupilot.userdata import ABOVE_HOME, ABSOLUTE, LATLON_TO_M, Location
from analyzer.ardupilot.values import UInt32
from analyzer.export.ardupilot import SENT_COMMANDS
from analyzer.protocol.codec import encode_command, find_command
from analyzer.protocol.crc import crc16
from analyzer.protocol.feedback import LAYOUTS, decode_feedback, encode_feedback
from analyzer.protocol.fields import EncodeError, Field
from analyzer.protocol.uav import encode_altitude, encode_gps, encode_uav_attitude
from tests.ardupilot_lua import ardupilot_lua, driver_functions

# Lua built as ArduPilot builds it: seconds, once per process.
pytestmark = pytest.mark.slow

__all__ = ["ardupilot_lua"]  # the fixture

f32 = np.float32
SEED = 46


class Driver:
    """The opened driver on ArduPilot's Lua: its locals, and Lua tables made from bytes."""

    def __init__(self, lua: ModuleType) -> None:
        self.fns, self.script = driver_functions(lua)
        self.codec = self.fns.codec

    def table(self, values: Any) -> Any:
        return self.script.lua.table_from(list(values))

    def bytes_of(self, table: Any) -> bytes:
        return bytes(table[i] for i in range(1, len(table) + 1))


@pytest.fixture(scope="module")
def driver(ardupilot_lua: ModuleType) -> Driver:
    return Driver(ardupilot_lua)


def float32_values(f: Field, rng: random.Random) -> Iterator[float]:
    """Physical values for a field, as float32: across and past its range, ties, zeros."""
    lo, hi = f.raw_limits()
    scale = f.mul / f.div
    yield 0.0
    yield float(f32(lo * scale))
    yield float(f32(hi * scale))
    for _ in range(40):
        yield float(f32(rng.uniform((lo - 50) * scale, (hi + 50) * scale)))
    for _ in range(10):  # a tie in raw units (exact where the scale is a power of two)
        yield float(f32((rng.randrange(lo, hi) + 0.5) * scale))


def expected_value(f: Field, value: float) -> float:
    """What the Python encoder writes for a float32 value: its own rounding, and where it
    refuses a value out of range, the nearest end of the range (the driver clamps)."""
    try:
        f.to_raw(value)
        return value
    except EncodeError:
        lo, hi = f.raw_limits()
        return f.scale(lo if value * f.div / f.mul < lo else hi)


def command_cases(rng: random.Random) -> Iterator[tuple[str, dict[str, Any]]]:
    """(command, raw label codes and float32 numbers for every field it sends)."""
    for name in SENT_COMMANDS:
        row = find_command(name, s_id="gimbal")
        variants = row.variants.items() if row.selector is not None else [(None, ())]
        for choice, variant in variants:
            fields = [*row.params, *variant]
            numbers = [f for f in fields if f.labels is None]
            columns = [list(float32_values(f, rng)) for f in numbers] or [[0.0]]
            for i in range(max(len(c) for c in columns)):
                values: dict[str, Any] = {}
                if row.selector is not None:
                    values[row.selector.name] = choice
                for f in fields:
                    if f.labels is not None:
                        values[f.name] = rng.choice([*f.labels, *([0] if f.other_label else [])])
                for f, column in zip(numbers, columns, strict=False):
                    values[f.name] = column[i % len(column)]
                yield name, values


def test_the_crc_is_the_protocols(driver: Driver) -> None:
    rng = random.Random(SEED)
    for _ in range(300):
        data = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 40)))
        assert driver.codec.crc16(driver.table(data), len(data)) == crc16(data), data.hex()


def test_every_command_the_driver_sends_has_the_python_encoders_bytes(driver: Driver) -> None:
    rng = random.Random(SEED)
    count = 0
    for name, values in command_cases(rng):
        fields = {f.name: f for f in find_command(name, s_id="gimbal").all_fields()}
        ours = driver.bytes_of(
            driver.codec.encode_command(name, driver.script.lua.table_from(values))
        )
        python = {k: v if fields[k].labels is not None else expected_value(fields[k], v)
                  for k, v in values.items()}  # fmt: skip
        assert ours == encode_command(name, s_id="gimbal", **python), (name, values)
        count += 1
    assert count > 400


def test_what_the_driver_computes_before_encoding_follows_float32(driver: Driver) -> None:
    """Tracking boxes and zoom ratios: the driver's float32 arithmetic, then the encoder."""
    rng = random.Random(SEED)
    size = f32(driver.fns.PROTOCOL.image_size - 1)
    for _ in range(200):
        x1, y1, x2, y2 = (f32(rng.random()) for _ in range(4))
        box = driver.fns.tracking_values(2, float(x1), float(y1), float(x2), float(y2))
        ours = driver.bytes_of(driver.codec.encode_command("tracking", box))
        want = {
            "x": (x1 + x2) / f32(2) * size,
            "y": (y1 + y2) / f32(2) * size,
            "width": abs(x2 - x1) * size,
            "height": abs(y2 - y1) * size,
        }
        fields = {f.name: f for f in find_command("tracking", s_id="gimbal").params}
        python = {k: expected_value(fields[k], float(v)) for k, v in want.items()}
        assert ours == encode_command("tracking", s_id="gimbal", **python), (x1, y1, x2, y2)
    zoom_max = 30.0  # VSH_ZOOM_MAX's default
    for percent in [*range(0, 101), *(rng.uniform(0, 100) for _ in range(100))]:
        value = f32(percent)
        ratio = f32(1) + (f32(zoom_max) - f32(1)) * value / f32(100)
        assert driver.fns.zoom_ratio(float(value)) == float(ratio)


def test_the_status_frames_have_the_python_encoders_bytes(driver: Driver) -> None:
    rng = random.Random(SEED)
    for _ in range(500):
        pitch, roll, yaw = (float(f32(rng.uniform(-179.99, 179.99))) for _ in range(3))
        pitch = float(f32(rng.uniform(-90, 90)))
        ours = driver.bytes_of(driver.codec.attitude_frame(pitch, roll, yaw))
        assert ours == encode_uav_attitude(pitch, roll, yaw), (pitch, roll, yaw)
        altitude = float(f32(rng.uniform(-500, 10_000)))
        assert driver.bytes_of(driver.codec.altitude_frame(altitude)) == encode_altitude(altitude)
        lat, lng = (
            rng.randrange(-900_000_000, 900_000_001),
            rng.randrange(-1_800_000_000, 1_800_000_001),
        )
        ours = driver.bytes_of(driver.codec.gps_frame(Location(lat, lng)))
        assert ours == encode_gps(lat / 1e7, lng / 1e7), (lat, lng)


def feedback_messages(rng: random.Random) -> Iterator[bytes]:
    for layout in LAYOUTS.values():
        for _ in range(200):
            values: dict[str, Any] = {}
            for f in layout.layout.fields:
                if f.labels is not None:
                    values[f.name] = rng.choice(list(f.labels.values()))
                elif f.boolean:
                    values[f.name] = rng.random() < 0.5
                else:
                    lo, hi = f.raw_limits()
                    values[f.name] = f.scale(rng.randint(lo, hi))
            yield encode_feedback(layout, **values)


def test_the_feedback_the_driver_parses_is_the_decoders(driver: Driver) -> None:
    rng = random.Random(SEED)
    for message in feedback_messages(rng):
        layout, decoded, _ = decode_feedback(message)
        assert layout is not None
        table = driver.table(message)
        assert driver.codec.message_ok(table), message.hex()
        lua_fields = driver.fns.FEEDBACK[message[2]].fields
        for f in layout.layout.fields:
            assert driver.codec.get_raw(table, lua_fields[f.name]) == f.read_raw(message), f.name
        if layout.name == "attitude":
            pitch, yaw = driver.fns.message_attitude(table)
            by_name = {f.name: f for f in layout.layout.fields}
            raw_pitch = by_name["pitch_deg"].read_raw(message)
            raw_yaw = by_name["motor_yaw_deg"].read_raw(message)
            assert pitch == float(f32(raw_pitch) / f32(100))
            assert yaw == float(wrap_180_f32(f32(raw_yaw) / f32(100)))
            assert pitch == pytest.approx(decoded["pitch_deg"], abs=1e-4)
            difference = (yaw - decoded["motor_yaw_deg"] + 180) % 360 - 180
            assert difference == pytest.approx(0, abs=1e-4)
        damaged = bytearray(message)
        at = rng.choice([i for i in range(layout.crc_offset + 2) if i != 2])  # not its length
        damaged[at] ^= 1 << rng.randrange(8)
        assert not driver.codec.message_ok(driver.table(damaged)), (message.hex(), at)


def wrap_180_f32(angle: np.float32) -> np.float32:
    """The driver's wrap_180 in float32 steps (math.fmod, then +-360)."""
    res = np.fmod(angle, f32(360.0))
    if res < 0:
        res = res + f32(360.0)
    if res > 180:
        res = res - f32(360.0)
    return np.float32(res)


def test_the_angles_to_a_location_target_are_the_reference_angles(driver: Driver) -> None:
    """Pitch and yaw raw values as a double-precision computation from the same inputs
    finds them (float32 can only differ within 1e-4 deg of a rounding boundary)."""
    rng = random.Random(SEED)
    angle = find_command("specified_angle", s_id="gimbal")
    fields = {f.name: f for variant in angle.variants.values() for f in variant}
    home_cm = 5000
    close = 0
    for _ in range(300):
        here = Location(rng.randrange(-600_000_000, 600_000_000),
                        rng.randrange(-1_700_000_000, 1_700_000_000),
                        home_cm + rng.randrange(0, 50_000), ABSOLUTE, home_cm)  # fmt: skip
        target = Location(here.lat() + rng.randrange(-20_000, 20_000),  # type: ignore[operator]
                          here.lng() + rng.randrange(-20_000, 20_000),  # type: ignore[operator]
                          rng.randrange(-2_000, 5_000), ABOVE_HOME, home_cm)  # fmt: skip
        pitch, yaw = driver.fns.angles_to(here, target)
        north, east = reference_ne(here, target)
        up_m = (target.alt() - (here.alt() - home_cm)) * 0.01  # type: ignore[operator]
        want_pitch = math.degrees(math.atan2(up_m, math.hypot(north, east)))
        want_yaw = math.degrees(math.atan2(east, north)) % 360
        assert pitch == pytest.approx(want_pitch, abs=1e-4)
        assert yaw == pytest.approx(want_yaw, abs=1e-4) or abs(yaw - want_yaw) > 359.99
        for name, ours, want in (("pitch_deg", pitch, want_pitch), ("yaw_deg", yaw, want_yaw)):
            f = fields[name]
            lua_raw = driver.codec.raw_value(driver.fns.COMMANDS.specified_angle.fields[name], ours)
            python_raw = min(max(round(want * f.div / f.mul), f.raw_limits()[0]), f.raw_limits()[1])
            # the driver's angle, as it computed it, is encoded as the Python encoder does
            assert lua_raw == f.to_raw(ours), (name, ours)
            tie_distance = abs((want * f.div / f.mul) % 1 - 0.5)
            if tie_distance < 1e-3:
                close += 1
                assert abs(lua_raw - python_raw) <= 1
            else:
                assert lua_raw == python_raw, (name, ours, want)
    assert close <= 3  # float32 can only tell these apart near a rounding boundary


def reference_ne(here: Location, target: Location) -> tuple[float, float]:
    """ArduPilot's Location:get_distance_NE in doubles, handed to Lua as float32."""
    lat1, lat2 = here.lat(), target.lat()
    scale = math.cos(math.radians((lat1 + lat2) / 2 * 1e-7))  # type: ignore[operator]
    north = (lat2 - lat1) * LATLON_TO_M  # type: ignore[operator]
    east = (target.lng() - here.lng()) * LATLON_TO_M * scale  # type: ignore[operator]
    return float(f32(north)), float(f32(east))


@pytest.mark.parametrize("start", [2**31 - 2000, 2**32 - 2000, 2**31 + 5000])
def test_timers_keep_their_schedule_across_the_wraps_of_millis(driver: Driver, start: int) -> None:
    """A 100 ms timer fires every 100 ms of millis() whatever millis() is, through its
    sign change at 2^31 and its wrap at 2^32 (and from the first update after either)."""
    timer = driver.fns.new_timer(100, 5)
    fired = [
        now for now in range(start, start + 4000, 10) if driver.fns.timer_due(timer, UInt32(now))
    ]
    assert fired == list(range(start, start + 4000, 100))
