"""The emulated ArduPilot scripting API is ArduPilot's: names and arguments from docs.lua,
and the semantics a driver depends on (scheduling, microseconds, extended IDs, integers)."""

from __future__ import annotations

import re
from functools import cache

import pytest

from analyzer.ardupilot.autopilot import BOOT_MS, Autopilot
from analyzer.ardupilot.binding import Binding
from analyzer.ardupilot.script import LuaScript, ScriptFailed, compile_check
from analyzer.ardupilot.session import Session, run_session
from analyzer.ardupilot.singletons import BINDING_CLASSES, lua_globals
from analyzer.ardupilot.userdata import (
    CameraStateUD,
    CANFrame,
    Location,
    ScriptingCANBuffer,
    Vector2f,
    Vector3f,
)
from analyzer.ardupilot.vehicle import Vehicle
from analyzer.export.ardupilot import DRIVER_NAME, lua_text
from analyzer.protocol.types import CanFrame
from tests.ardupilot_docs import (
    BUFFER_LEN,
    EXTENDED_FLAG,
    GPS_CONSTANTS,
    INT_BITS,
    SIGNATURES,
    arities,
)

USERDATA = (CANFrame, ScriptingCANBuffer, Location, Vector2f, Vector3f, CameraStateUD)
SINGLETON_NAMES = ("CAN", "mount", "camera", "ahrs", "gps", "param", "gcs")


@cache
def demo_session() -> Session:
    return run_session(lua_text(), DRIVER_NAME, 24.0)


def emulated_signatures() -> dict[tuple[str, str], tuple[str, ...]]:
    """Every binding the emulation gives a script, with its parameters ('?' optional)."""
    out: dict[tuple[str, str], tuple[str, ...]] = {}
    classes: tuple[type[Binding], ...] = (*BINDING_CLASSES, *USERDATA)
    for cls in classes:
        for name, sig in cls.signatures().items():
            required = len(sig.params) - sig.optional
            out[(cls.lua_class, name)] = tuple(
                p if i < required else p + "?" for i, p in enumerate(sig.params)
            )
    vehicle = Vehicle(lambda *_: True)
    for name, value in lua_globals(vehicle, demo_session().script.log).items():
        if name in SINGLETON_NAMES:
            continue
        sig = value.signature
        required = len(sig.params) - sig.optional
        out[("", name)] = tuple(p if i < required else p + "?" for i, p in enumerate(sig.params))
    out[("uint32_t_ud", "toint")] = ()
    out[("uint32_t_ud", "tofloat")] = ()
    return out


@pytest.mark.slow
def test_every_emulated_binding_has_docs_lua_name_and_parameters() -> None:
    emulated = emulated_signatures()
    unknown = sorted(set(emulated) - set(SIGNATURES))
    assert not unknown, f"not in ArduPilot's docs.lua: {unknown}"
    for key, params in emulated.items():
        assert params == SIGNATURES[key], (key, params, SIGNATURES[key])


def test_singletons_are_the_names_a_script_sees_and_gps_has_its_enum() -> None:
    vehicle = Vehicle(lambda *_: True)
    given = lua_globals(vehicle, demo_session().script.log)
    assert set(SINGLETON_NAMES) <= set(given)
    assert given["gps"].lua_constants == GPS_CONSTANTS


def test_every_call_of_the_driver_is_in_docs_lua_with_its_argument_count() -> None:
    calls = demo_session().script.log.calls
    assert calls, "the driver called nothing"
    for (cls, name, count), _ in calls.items():
        assert (cls, name) in SIGNATURES, f"{cls}:{name} is not in docs.lua"
        assert count in arities(SIGNATURES[(cls, name)]), (cls, name, count)


def test_every_method_named_in_the_driver_source_is_in_docs_lua() -> None:
    text = lua_text()
    documented = {name for _, name in SIGNATURES}
    body = re.sub(r"--.*", "", text)  # comments aside
    for obj, name in re.findall(r"\b(\w+):(\w+)\(", body):
        if obj in SINGLETON_NAMES:
            assert (obj, name) in SIGNATURES, f"{obj}:{name}"
        else:
            assert name in documented, f"{obj}:{name}"
    for name in ("millis", "uint32_t", "CANFrame", "Parameter"):
        assert re.search(rf"\b{name}\(", body)
        assert ("", name) in SIGNATURES
    # gps's enum, as docs.lua spells it
    for constant in re.findall(r"(?<![.\w])gps\.(\w+)", body):
        assert constant in GPS_CONSTANTS


def _script(source: str, vehicle: Vehicle | None = None) -> LuaScript:
    return LuaScript(source, "t.lua", vehicle or Vehicle(lambda *_: True))


def test_update_returns_itself_and_its_period_in_ms() -> None:
    script = _script(
        "local n = 0\nfunction update() n = n + 1 return update, 25 end\nreturn update()"
    )
    script.start(1000)
    assert script.due_ms == 1025
    script.run(1025)
    assert script.due_ms == 1050
    ended = _script("return")
    ended.start(0)
    assert ended.due_ms is None and ended.error is None
    wrong = _script("function update() return update, 'soon' end\nreturn update()")
    with pytest.raises(ScriptFailed, match="must return a function and a time in ms"):
        wrong.start(0)


def test_a_script_error_names_file_and_line() -> None:
    script = _script("local x = nil\nfunction update()\n  return x.y, 10\nend\nreturn update()")
    with pytest.raises(ScriptFailed, match=r"^Lua: t\.lua:3: attempt to index"):
        script.start(0)
    bad_arg = _script("function update()\n  gcs:send_text(9, 'x')\nend\nreturn update()")
    with pytest.raises(ScriptFailed, match=r"t\.lua:2: gcs:send_text: severity 9"):
        bad_arg.start(0)
    with pytest.raises(ScriptFailed, match=r"t\.lua:1:"):
        compile_check("local = 1", "t.lua")


def test_methods_need_their_object_and_their_exact_arguments() -> None:
    with pytest.raises(ScriptFailed, match="called without its object"):
        _script("mount.get_rate_target(0)").start(0)
    with pytest.raises(ScriptFailed, match="got 0 arguments, expected 1"):
        _script("mount:get_rate_target()").start(0)
    # CAN:get_device takes '.' as well as ':', as ArduPilot's lua_get_CAN_device does
    vehicle = Vehicle(lambda *_: True)
    _script("assert(CAN.get_device(5)) assert(CAN:get_device(5))", vehicle).start(0)
    lo, hi = BUFFER_LEN
    with pytest.raises(ScriptFailed, match="out of range"):
        _script(f"CAN:get_device({hi + 1})").start(0)
    _script(f"CAN:get_device({lo})").start(0)


def test_write_frame_timeout_is_in_microseconds_and_the_driver_waits_10_ms() -> None:
    devices = demo_session().vehicle.devices
    assert list(devices) == [1]
    timeouts = set(devices[1].timeouts_us)
    assert timeouts == {10_000}  # 10 ms: ArduPilot's drivers pass 10000 too


def test_extended_ids_carry_bit_31_and_a_frame_without_it_goes_out_standard() -> None:
    sent: list[tuple[int, bytes, bool]] = []
    vehicle = Vehicle(lambda i, d, e: sent.append((i, d, e)) or True)
    _script(
        f"""
        local bus = CAN:get_device(1)
        local f = CANFrame()
        f:id(uint32_t(0x00000F01) | (uint32_t(1) << 31))  -- {EXTENDED_FLAG:#x}
        f:dlc(2) f:data(0, 0x0F) f:data(1, 0x02)
        assert(f:isExtended() and f:id_signed() == 0xF01)
        bus:write_frame(f, 10000)
        local g = CANFrame()
        g:id(0x00000F01) g:dlc(0)
        assert(not g:isExtended())
        bus:write_frame(g, 10000)
        """,
        vehicle,
    ).start(0)
    # without bit 31 the ID is an 11-bit one: 0xF01 goes out as standard 0x701
    assert sent == [(0xF01, b"\x0f\x02", True), (0x701, b"", False)]
    # and a frame received on an extended ID reads back with the flag
    reader = _script(
        "local bus = CAN:get_device(1)\n"
        "function update()\n"
        "  local f = bus:read_frame()\n"
        "  assert(f:id() == uint32_t(0x030F0001) | (uint32_t(1) << 31))\n"
        "  assert(f:isExtended() and f:id_signed() == 0x030F0001 and f:data(1) == 0x90)\n"
        "end\n"
        "return update, 10",
        vehicle,
    )
    reader.start(0)
    vehicle.deliver(0x030F0001, b"\xeb\x90", True)
    assert vehicle.devices[1].received[0].raw_id == 0x030F0001 | EXTENDED_FLAG
    reader.run(10)
    assert reader.error is None and reader.due_ms is None


def test_lua_integers_are_lua_5_3_integers_of_32_bits() -> None:
    # a float with a fraction is no integer for a binding (luaL_checkinteger)
    with pytest.raises(ScriptFailed, match="no integer representation"):
        _script("CANFrame():data(0, 1.5)").start(0)
    _script("CANFrame():data(0, 2.0) assert(math.type(1 // 1) == 'integer')").start(0)
    # ArduPilot's lua_Integer has 32 bits: a wider integer never reaches a binding
    with pytest.raises(ScriptFailed, match="does not fit a 32-bit Lua integer"):
        _script(f"CANFrame():dlc({2**INT_BITS})").start(0)
    # uint32_t wraps modulo 2^32, toint gives the 32-bit integer
    _script(
        "local u = uint32_t(0) - 1\n"
        "assert(u == (uint32_t(0xFFFF) << 16 | 0xFFFF) and u:toint() == -1)\n"
        "assert(millis() - uint32_t(5) > 1000)"
    ).start(1010)


def test_driver_integer_literals_fit_a_32_bit_lua_integer() -> None:
    body = re.sub(r"--.*", "", lua_text())
    for literal in re.findall(r"(?<![\w.])(0[xX][0-9a-fA-F]+|\d+)(?![\w.])", body):
        assert int(literal, 0) < 2 ** (INT_BITS - 1), literal


def test_a_run_over_the_instruction_limit_stops_the_script_and_the_driver_is_far_below() -> None:
    with pytest.raises(ScriptFailed, match="exceeded time limit"):
        _script("function update() while true do end end\nreturn update()").start(0)
    used = demo_session().script.max_instructions
    assert used <= 10_000 // 2, used  # SCR_VM_I_COUNT's default is 10000


def test_the_autopilot_is_one_sans_io_loop_of_steps() -> None:
    """step(now_ms, received): the first step loads the script, frames reach its CAN buffer
    before it runs, it runs only when due; what it did comes back as values."""
    sent: list[tuple[int, bytes, bool]] = []
    source = (
        "local bus = CAN:get_device(5)\n"
        "function update()\n"
        "  local f = bus:read_frame()\n"
        "  if f then\n"
        "    gcs:send_text(6, string.format('got %d', f:data(0)))\n"
        "    mount:set_attitude_euler(0, 0, f:data(0), 0)\n"
        "    bus:write_frame(f, 10000)\n"
        "  end\n"
        "  if millis() > uint32_t(1200) then error('done') end\n"
        "  return update, 50\n"
        "end\n"
        "return update()\n"
    )
    autopilot = Autopilot(source, "loop.lua", lambda *frame: sent.append(frame) or True)
    first = autopilot.step(BOOT_MS, [CanFrame(0.0, 0x030F0001, b"\x07", True, "can0")])
    assert (first.due_ms, first.texts, first.error) == (BOOT_MS + 50, [], None)
    frame = CanFrame(0.0, 0x030F0001, b"\x2a", True, "can0")
    early = autopilot.step(BOOT_MS + 20, [frame])  # not due: the frame waits in the buffer
    assert (early.due_ms, early.texts, early.events) == (BOOT_MS + 50, [], [])
    due = autopilot.step(BOOT_MS + 50)
    assert due.texts == ["got 7"] and sent == [(0x030F0001, b"\x07", True)]
    assert [e.fields["pitch_deg"] for e in due.events] == [7.0]
    assert autopilot.step(BOOT_MS + 100).texts == ["got 42"]
    failed = autopilot.step(BOOT_MS + 250)
    assert failed.due_ms is None and failed.error is not None
    assert failed.error.startswith("Lua: loop.lua:9: done")
