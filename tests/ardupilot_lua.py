"""Lua built as ArduPilot builds it, for the tests (built once into pytest's cache), and the
generated driver opened up: its chunk returning its own functions and tables.

Building needs pip to reach PyPI (lupa's sdist) and a C compiler; without them the tests
that need it skip, unless ``GIMBAL_REQUIRE_ARDUPILOT_LUA=1`` (as in ``.ci/run``).
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

from analyzer.ardupilot.lua_build import BuildError, build, load
from analyzer.ardupilot.script import LuaScript
from analyzer.ardupilot.vehicle import Vehicle
from analyzer.export.ardupilot import DRIVER_NAME, lua_text

REQUIRE = os.environ.get("GIMBAL_REQUIRE_ARDUPILOT_LUA") == "1"

# What the opened driver hands the tests (its locals, by name).
EXPOSED = (
    "PROTOCOL",
    "COMMANDS",
    "FEEDBACK",
    "STATUS",
    "codec",
    "message_attitude",
    "angles_to",
    "tracking_values",
    "zoom_ratio",
    "new_timer",
    "timer_due",
    "wrap_180",
)


def build_cache(config: pytest.Config, tmp_path_factory: pytest.TempPathFactory) -> Path:
    cache = getattr(config, "cache", None)
    if cache is not None:
        return Path(cache.mkdir("ardupilot-lua"))
    return tmp_path_factory.mktemp("ardupilot-lua")


@pytest.fixture(scope="session")
def ardupilot_lua(
    pytestconfig: pytest.Config, tmp_path_factory: pytest.TempPathFactory
) -> ModuleType:
    """lupa's LuaRuntime on Lua 5.3 built with ArduPilot's LUA_32BITS and limits."""
    try:
        return load(build(build_cache(pytestconfig, tmp_path_factory)))
    except BuildError as exc:
        if REQUIRE:
            pytest.fail(f"ArduPilot's Lua could not be built: {exc}")
        pytest.skip(f"ArduPilot's Lua could not be built: {exc}")


def opened_driver(text: str | None = None) -> str:
    """The driver whose chunk returns a table of its own locals instead of running."""
    source = text if text is not None else lua_text()
    ending = "\nreturn update()\n"
    assert source.endswith(ending)
    names = ", ".join(f"{name} = {name}" for name in EXPOSED)
    return source[: -len(ending)] + f"\nreturn {{{names}}}\n"


def driver_functions(lua: ModuleType | None, vehicle: Vehicle | None = None) -> tuple[Any, Any]:
    """(the driver's locals as a Lua table, the LuaScript) on an emulated autopilot."""
    script = LuaScript(opened_driver(), DRIVER_NAME, vehicle or Vehicle(lambda *_: True), lua=lua)
    return script.chunk(), script


def with_locals(count: int, text: str | None = None) -> str:
    """The driver with ``count`` more locals at its top level (declared before its end)."""
    source = text if text is not None else lua_text()
    names = [f"_pad{n}" for n in range(count)]
    pads = "".join(f"local {name} = {n}\n" for n, name in enumerate(names))
    return re.sub(r"\nreturn update\(\)\n$", "\n" + pads + "return update()\n", source)
