"""A Lua script run as ArduPilot runs it: Lua 5.3 (lupa), sandboxed, rescheduled by its own
``return update, ms``, stopped by an error or by too many instructions in one run."""

from __future__ import annotations

import re
from typing import Any

from analyzer.ardupilot.binding import CallLog, attribute_getter, attribute_setter
from analyzer.ardupilot.singletons import lua_globals
from analyzer.ardupilot.values import UInt32, uint32_metamethods
from analyzer.ardupilot.vehicle import Vehicle

HOOK_STEP = 100  # instructions between two counts (the limit is checked this finely)
# What ArduPilot's sandbox gives every script besides the bindings (no io, os or debug)
SAFE_NAMES = (
    "assert",
    "error",
    "ipairs",
    "next",
    "pairs",
    "pcall",
    "select",
    "tonumber",
    "tostring",
    "type",
    "xpcall",
    "rawequal",
    "rawget",
    "rawlen",
    "rawset",
    "setmetatable",
    "getmetatable",
    "string",
    "table",
    "math",
    "utf8",
    "_VERSION",
)

_PRELUDE = """
local names, hook_step = ...
local sethook, traceback = debug.sethook, debug.traceback
local env_template = {}
for _, name in ipairs(names) do env_template[name] = _G[name] end

local function new_env(bindings)
  local env = {}
  for name, value in pairs(env_template) do env[name] = value end
  for name, value in pairs(bindings) do env[name] = value end
  return env
end

-- run fn with at most `limit` instructions; returns the instructions used, then xpcall's
local function run(fn, limit)
  local steps = 0
  sethook(function()
    steps = steps + 1
    if steps * hook_step >= limit then
      error("exceeded time limit", 2)
    end
  end, "", hook_step)
  local results = table.pack(xpcall(fn, function(err)
    return {err, traceback("", 2)}
  end))
  sethook()
  return steps * hook_step, table.unpack(results, 1, results.n)
end
return new_env, run
"""


class ScriptFailed(Exception):
    """The script stopped with an error, as ArduPilot reports it (``Lua: <where>: <why>``)."""


class LuaScript:
    """One script file on the emulated autopilot ``vehicle``.

    ``start()`` runs the chunk (ArduPilot's load), ``run(now_ms)`` the function it asked
    for when due; ``due_ms`` is when that is (None once the script ended or failed, then
    ``error`` says why). ``log`` counts every binding called."""

    def __init__(self, source: str, name: str, vehicle: Vehicle) -> None:
        import lupa.lua53 as lua53

        self.name = name
        self.vehicle = vehicle
        self.log = CallLog()
        self.lua = lua53.LuaRuntime(
            unpack_returned_tuples=True,
            register_eval=False,
            register_builtins=False,
            attribute_handlers=(attribute_getter(self.log), attribute_setter),
        )
        metatable = self.lua.eval("getmetatable")(UInt32(0))
        for key, fn in uint32_metamethods().items():
            metatable[key] = fn
        prelude = self.lua.execute(_PRELUDE, self.lua.table_from(SAFE_NAMES), HOOK_STEP)
        new_env, self._run = prelude
        env = new_env(self.lua.table_from(lua_globals(vehicle, self.log)))
        loaded = self.lua.globals().load(source, "@" + name, "t", env)
        if isinstance(loaded, tuple):  # (nil, why): it does not compile
            raise ScriptFailed(f"Lua: {loaded[1]}")
        self._next: Any = loaded
        self.due_ms: int | None = None
        self.error: str | None = None
        self.runs = 0
        self.max_instructions = 0

    @property
    def instruction_limit(self) -> int:
        return int(self.vehicle.parameters.get("SCR_VM_I_COUNT", 10000))

    def start(self, now_ms: int) -> None:
        """Run the chunk: what it returns says when to run next."""
        self.due_ms = now_ms
        self.run(now_ms)

    def run(self, now_ms: int) -> None:
        """Run the scheduled function (the clock stands at ``now_ms``); raises ScriptFailed."""
        if self.due_ms is None or self._next is None:
            return
        self.vehicle.advance(now_ms)
        used, ok, *results = self._run(self._next, self.instruction_limit)
        self.runs += 1
        self.max_instructions = max(self.max_instructions, used)
        if not ok:
            self._fail(self._describe(results[0]))
        if not results or results[0] is None:
            self.due_ms, self._next = None, None  # the script ended
            return
        fn = results[0]
        delay = results[1] if len(results) > 1 else None
        if self.lua.eval("type")(fn) != "function" or not _is_integer(delay):
            self._fail("Scripts must return a function and a time in ms (or nothing)")
        self._next = fn
        self.due_ms = now_ms + int(delay or 0)

    def _fail(self, why: str) -> None:
        self.error = f"Lua: {why}"
        self.due_ms, self._next = None, None
        raise ScriptFailed(self.error)

    def _describe(self, failure: Any) -> str:
        """``<file>:<line>: <message>`` of an error (a Lua one, or a binding's)."""
        err, trace = (failure[1], failure[2]) if hasattr(failure, "values") else (failure, "")
        message = str(err)
        if re.match(rf"{re.escape(self.name)}:\d+:", message):
            return message
        match = re.search(rf"{re.escape(self.name)}:(\d+):", str(trace))
        return f"{self.name}:{match.group(1)}: {message}" if match else message


def _is_integer(value: Any) -> bool:
    if isinstance(value, bool):
        return False
    return isinstance(value, int) or (isinstance(value, float) and value.is_integer())


def compile_check(source: str, name: str) -> None:
    """Raise ScriptFailed (``Lua: <file>:<line>: <why>``) when ``source`` does not compile."""
    import lupa.lua53 as lua53

    lua = lua53.LuaRuntime(register_eval=False, register_builtins=False)
    loaded = lua.globals().load(source, "@" + name, "t")
    if isinstance(loaded, tuple):
        raise ScriptFailed(f"Lua: {loaded[1]}")
