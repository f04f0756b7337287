"""The generated driver loads on Lua built as ArduPilot builds it (lupa's Lua 5.3 sources,
LUA_32BITS, MAXVARS 100, MAXUPVAL 127) and runs the demo there; a script past a limit is
refused with ArduPilot's message, and the driver's heap is what the manual says."""

from __future__ import annotations

import re
from pathlib import Path
from types import ModuleType

import pytest

from analyzer.ardupilot.lua_build import LIMITS, MAX_LOCALS
from analyzer.ardupilot.script import ScriptFailed, compile_check
from analyzer.ardupilot.session import run_session
from analyzer.export.ardupilot import DRIVER_NAME, lua_text
from analyzer.export.ardupilot_params import AUTOPILOT_PARAMETERS
from tests.ardupilot_lua import ardupilot_lua, with_locals

# Lua built as ArduPilot builds it: seconds, once per process.
pytestmark = pytest.mark.slow

__all__ = ["ardupilot_lua"]  # the fixture

MANUAL = (Path(__file__).resolve().parents[1] / "docs" / "howto" / "ardupilot.md").read_text(
    encoding="utf-8"
)
TOO_MANY = re.escape(f"too many local variables (limit is {MAX_LOCALS}) in main function")
HEADROOM = 30  # locals an edited copy may add at the driver's top level


def locals_chunk(count: int) -> str:
    return "".join(f"local v{n} = {n}\n" for n in range(count))


def test_the_interpreter_has_32_bit_numbers_and_arduPilots_limits(
    ardupilot_lua: ModuleType,
) -> None:
    lua = ardupilot_lua.LuaRuntime()
    assert lua.eval("math.maxinteger") == 2**31 - 1
    assert lua.eval("16777217.0 == 16777216.0")  # a 24-bit mantissa: a 32-bit float
    assert lua.eval("1 << 31") == -(2**31) and lua.eval("(1 << 32)") == 0
    assert lua.eval("_VERSION") == "Lua 5.3"
    compile_check(locals_chunk(MAX_LOCALS), "t.lua", lua=ardupilot_lua)
    with pytest.raises(ScriptFailed, match=rf"t\.lua:{MAX_LOCALS + 1}: {TOO_MANY}"):
        compile_check(locals_chunk(MAX_LOCALS + 1), "t.lua", lua=ardupilot_lua)
    # lupa's own Lua (200 locals) accepts what ArduPilot's refuses
    compile_check(locals_chunk(MAX_LOCALS + 1), "t.lua")
    upvalues = {limit.name: limit for limit in LIMITS}["MAXUPVAL"].ardupilot.split()[-1]
    most = int(upvalues)
    half = (most + 2) // 2  # locals of two enclosing functions: the inner one sees most + 1
    outer = "".join(f"local a{n} = {n}\n" for n in range(half))
    middle = "".join(f"local b{n} = {n}\n" for n in range(half))
    uses = " + ".join([f"a{n}" for n in range(half)] + [f"b{n}" for n in range(half)])
    chunk = f"{outer}return function()\n{middle}return function() return {uses} end\nend\n"
    with pytest.raises(ScriptFailed, match=f"too many upvalues \\(limit is {most}\\)"):
        compile_check(chunk, "u.lua", lua=ardupilot_lua)
    compile_check(chunk, "u.lua")  # 255 in lupa's


def test_the_driver_loads_and_leaves_room_for_more_locals(ardupilot_lua: ModuleType) -> None:
    compile_check(lua_text(), DRIVER_NAME, lua=ardupilot_lua)
    # how many locals can be added at the driver's top level before ArduPilot refuses it
    room = next(n for n in range(MAX_LOCALS + 1) if _refused(with_locals(n + 1), ardupilot_lua))
    assert room >= HEADROOM, f"only {room} more locals fit the driver's top level"
    # so its own top level holds MAX_LOCALS - room: one more than room makes it 101
    with pytest.raises(ScriptFailed, match=rf"^Lua: {DRIVER_NAME}:\d+: {TOO_MANY}"):
        compile_check(with_locals(room + 1), DRIVER_NAME, lua=ardupilot_lua)


def _refused(text: str, lua: ModuleType) -> bool:
    try:
        compile_check(text, DRIVER_NAME, lua=lua)
    except ScriptFailed:
        return True
    return False


def test_the_demo_plan_runs_there_and_its_heap_is_the_manuals(
    ardupilot_lua: ModuleType,
) -> None:
    session = run_session(lua_text(), DRIVER_NAME, 40.0, lua=ardupilot_lua)
    assert session.error is None, session.error
    script = session.script
    assert script.runs > 3900 and script.max_instructions <= 10_000 // 2
    # the manual's figures (kB) for this interpreter on this 64-bit computer
    row = re.search(r"^\| the tests' interpreter [^|]*\| (\d+) kB \| (\d+) kB", MANUAL, re.M)
    assert row is not None
    loaded, peak = (int(kb) * 1024 for kb in row.groups())
    assert script.heap_loaded == pytest.approx(loaded, rel=0.05)
    assert script.heap_peak == pytest.approx(peak, rel=0.05)
    heap = {p.name: p.value for p in AUTOPILOT_PARAMETERS}["SCR_HEAP_SIZE"]
    assert script.heap_loaded < heap  # even with this computer's 8-byte pointers
