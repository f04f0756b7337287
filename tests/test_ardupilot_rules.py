"""The generated driver keeps ArduPilot's rules, kept here as facts with their version: its
CI's luacheck (0 warnings, no inline options), the current API (no deprecated binding) and a
parameter table key no script shipped with ArduPilot uses."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from analyzer.ardupilot.script import LuaScript
from analyzer.ardupilot.session import run_session
from analyzer.ardupilot.singletons import BINDING_CLASSES
from analyzer.ardupilot.vehicle import Vehicle
from analyzer.export.ardupilot import DRIVER_NAME, lua_text
from analyzer.export.ardupilot_params import PARAM_TABLE_KEY
from tests.ardupilot_docs import DEPRECATED, SIGNATURES
from tests.ardupilot_scripts import (
    LUACHECK_ENUMS,
    TABLE_KEY_RANGE,
    TABLE_KEYS,
    docs_globals,
    luacheck_config,
)

LUACHECK = shutil.which("luacheck")
# With this set (.ci/run does), the luacheck tests fail instead of skipping without it.
REQUIRED = os.environ.get("GIMBAL_REQUIRE_LUACHECK") == "1"
needs_luacheck = pytest.mark.skipif(
    LUACHECK is None and not REQUIRED, reason="luacheck is not installed (Debian lua-check)"
)


def luacheck(tmp_path: Path, name: str, text: str) -> tuple[int, str]:
    """luacheck as ArduPilot's CI runs it (run_luacheck.sh) with its rules: code, report."""
    assert LUACHECK is not None, "luacheck is not installed (Debian package lua-check)"
    config = tmp_path / "ardupilot.luacheckrc"  # not luacheck.lua: it would shadow luacheck
    config.write_text(luacheck_config(), encoding="utf-8")
    (tmp_path / name).write_text(text, encoding="utf-8")
    done = subprocess.run(
        [LUACHECK, "--no-color", "--codes", name, "--config", config.name],
        capture_output=True,
        text=True,
        encoding="utf-8",
        timeout=120,
        cwd=tmp_path,
        check=False,
    )
    return done.returncode, done.stdout + done.stderr


@needs_luacheck
def test_luacheck_with_arduPilots_rules_finds_nothing_in_the_driver(tmp_path: Path) -> None:
    code, report = luacheck(tmp_path, DRIVER_NAME, lua_text())
    assert code == 0 and "0 warnings / 0 errors" in report, report
    assert "luacheck:" not in lua_text()  # no inline options: every rule applies


@needs_luacheck
def test_the_rules_are_arduPilots(tmp_path: Path) -> None:
    """What ArduPilot's CI reports and what it lets pass, on a small script."""
    script = "\n".join(
        [
            "local labels = {}",  # W311: assigned, and overwritten before any use
            "labels = {1}",
            "local function f(_unused, used) return used + labels[1] end",  # 212/_.* ignored
            "gcs:send_text(6, tostring(f(nil, 1)))",
            "ahrs:get_nothing()",  # W143: not a field docs.lua gives ahrs
            "undeclared_global = gps.GPS_OK_FIX_3D",  # W111 ignored; the enum is added
            "local x = 1" + " " * 130,  # W631 / W612 ignored
            "return x",
            "",
        ]
    )
    code, report = luacheck(tmp_path, "t.lua", script)
    assert code == 1
    found = re.findall(r"t\.lua:(\d+):\d+: \((W\d+)\)", report)
    assert found == [("1", "W311"), ("5", "W143")], report


def test_the_luacheck_globals_are_docs_luas_and_hold_every_binding_we_emulate() -> None:
    globals_ = docs_globals()
    for (cls, name), _ in SIGNATURES.items():
        if cls == "":
            assert name in globals_, name
        elif not cls.endswith("_ud"):  # a singleton: a table of docs.lua's globals
            assert name in (globals_[cls] or ()), (cls, name)
    assert set(LUACHECK_ENUMS) <= set(globals_)


def test_the_driver_calls_no_deprecated_binding() -> None:
    body = re.sub(r"--.*", "", lua_text())
    for obj, name in re.findall(r"\b(\w+):(\w+)\(", body):
        assert (obj, name) not in DEPRECATED, f"{obj}:{name} is deprecated"
    session = run_session(lua_text(), DRIVER_NAME, 21.0)
    called = {(cls, name) for cls, name, _ in session.script.log.calls}
    assert ("ahrs", "get_yaw_rad") in called
    assert not called & set(DEPRECATED), called & set(DEPRECATED)
    assert session.script.log.warnings == []


def test_a_deprecated_binding_warns_once_as_arduPilot_does() -> None:
    emulated = {
        (cls.lua_class, name): signature.deprecated
        for cls in BINDING_CLASSES
        for name, signature in cls.signatures().items()
        if signature.deprecated
    }
    assert emulated == {key: DEPRECATED[key] for key in emulated}
    vehicle = Vehicle(lambda *_: True)
    script = LuaScript(
        "function update() ahrs:get_roll() ahrs:get_roll() return update, 10 end\nreturn update()",
        "old.lua",
        vehicle,
    )
    script.start(1000)
    script.run(1010)
    assert [text for _, _, text in vehicle.texts] == ["Lua: ahrs:get_roll Use get_roll_rad"]


def test_the_parameter_table_key_is_one_no_arduPilot_script_uses() -> None:
    lo, hi = TABLE_KEY_RANGE
    assert lo <= PARAM_TABLE_KEY <= hi
    assert PARAM_TABLE_KEY not in TABLE_KEYS, TABLE_KEYS.get(PARAM_TABLE_KEY)
    assert f"local PARAM_TABLE_KEY = {PARAM_TABLE_KEY} " in lua_text()
    assert 87 in TABLE_KEYS  # the driver's first key: applets/ahrs-set-origin.lua has it
