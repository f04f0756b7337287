"""A Lua script run as ArduPilot runs it: Lua 5.3 (lupa), sandboxed, rescheduled by its own
``return update, ms``, stopped by an error or by too many instructions in one run."""

from __future__ import annotations

import re
from types import ModuleType
from typing import Any

from analyzer.ardupilot.binding import CallLog, attribute_getter, attribute_setter
from analyzer.ardupilot.singletons import lua_globals
from analyzer.ardupilot.values import UInt32, uint32_metamethods
from analyzer.ardupilot.vehicle import Vehicle

HOOK_STEP = 100  # instructions between two counts (the limit is checked this finely)
MAV_SEVERITY_WARNING = 4
# What ArduPilot's sandbox gives every script besides the bindings: lbaselib.c's base
# functions less the ones it comments out (collectgarbage, dofile, getmetatable, loadfile,
# print, rawequal, rawget, rawlen, rawset, select, xpcall), then math, table and string
# without string.dump (lua_scripts.cpp create_sandbox, lstrlib.c; no utf8, os, coroutine
# or debug). ArduPilot also gives load, io and package; the emulation leaves them out: its
# Lua's globals and files are not the autopilot's.
SAFE_NAMES = (
    "assert",
    "error",
    "ipairs",
    "next",
    "pairs",
    "pcall",
    "setmetatable",
    "tonumber",
    "tostring",
    "type",
    "string",
    "table",
    "math",
)

_PRELUDE = """
local names, hook_step = ...
local sethook, traceback = debug.sethook, debug.traceback
local env_template = {}
for _, name in ipairs(names) do env_template[name] = _G[name] end
local string_lib = {}
for name, fn in pairs(string) do
  if name ~= "dump" then string_lib[name] = fn end
end
env_template.string = string_lib

local function new_env(bindings)
  local env = {}
  for name, value in pairs(env_template) do env[name] = value end
  for name, value in pairs(bindings) do env[name] = value end
  return env
end

-- the heap in bytes (after a full collection when `full`), as collectgarbage counts it
local function heap(full)
  if full then collectgarbage("collect") end
  return math.floor(collectgarbage("count") * 1024)
end

-- run fn with at most `limit` instructions, then collect the garbage as ArduPilot does
-- after every run; returns the instructions used, the heap before that collection, then
-- xpcall's results
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
  local used = heap(false)
  collectgarbage("collect")
  return steps * hook_step, used, table.unpack(results, 1, results.n)
end
return new_env, run, heap
"""


class ScriptFailed(Exception):
    """The script stopped with an error, as ArduPilot reports it (``Lua: <where>: <why>``)."""


def stock_lua() -> ModuleType:
    """lupa's Lua 5.3 (64-bit integers and floats, stock limits)."""
    import lupa.lua53 as lua53

    return lua53


class LuaScript:
    """One script file on the emulated autopilot ``vehicle``, in ``lua`` (lupa's Lua 5.3,
    or a module of lua_build: Lua built as ArduPilot builds it).

    ``start()`` runs the chunk (ArduPilot's load), ``run(now_ms)`` the function it asked
    for when due; ``due_ms`` is when that is (None once the script ended or failed, then
    ``error`` says why). ``log`` counts every binding called. As ArduPilot does, the
    garbage is collected after every run: ``heap_loaded`` is the script's heap (bytes)
    once its chunk ran, ``heap_peak`` the most it held at the end of a run, garbage and
    all (lupa's wrappers of the bindings' Python objects too: ArduPilot has none)."""

    def __init__(
        self, source: str, name: str, vehicle: Vehicle, *, lua: ModuleType | None = None
    ) -> None:
        self.name = name
        self.vehicle = vehicle
        self.log = CallLog()
        self.lua = (lua or stock_lua()).LuaRuntime(
            unpack_returned_tuples=True,
            register_eval=False,
            register_builtins=False,
            attribute_handlers=(attribute_getter(self.log), attribute_setter),
        )
        metatable = self.lua.eval("getmetatable")(UInt32(0))
        for key, fn in uint32_metamethods().items():
            metatable[key] = fn
        prelude = self.lua.execute(_PRELUDE, self.lua.table_from(SAFE_NAMES), HOOK_STEP)
        new_env, self._run, self._heap = prelude
        env = new_env(self.lua.table_from(lua_globals(vehicle, self.log)))
        self._heap_base = int(self._heap(True))
        loaded = self.lua.globals().load(source, "@" + name, "t", env)
        if isinstance(loaded, tuple):  # (nil, why): it does not compile
            raise ScriptFailed(f"Lua: {loaded[1]}")
        self.chunk: Any = loaded  # the compiled chunk (a Lua function)
        self._next: Any = loaded
        self.due_ms: int | None = None
        self.error: str | None = None
        self.runs = 0
        self.max_instructions = 0
        self.heap_loaded = 0
        self.heap_peak = 0
        self._warned = 0

    @property
    def instruction_limit(self) -> int:
        return int(self.vehicle.parameters.get("SCR_VM_I_COUNT", 10000))

    def start(self, now_ms: int) -> None:
        """Run the chunk: what it returns says when to run next."""
        self.due_ms = now_ms
        try:
            self.run(now_ms)
        finally:
            self.heap_loaded = int(self._heap(False)) - self._heap_base

    def run(self, now_ms: int) -> None:
        """Run the scheduled function (the clock stands at ``now_ms``); raises ScriptFailed."""
        if self.due_ms is None or self._next is None:
            return
        self.vehicle.advance(now_ms)
        used, heap, ok, *results = self._run(self._next, self.instruction_limit)
        self.runs += 1
        self.max_instructions = max(self.max_instructions, used)
        self.heap_peak = max(self.heap_peak, int(heap) - self._heap_base)
        for warning in self.log.warnings[self._warned :]:
            self.vehicle.send_text(MAV_SEVERITY_WARNING, f"Lua: {warning}")
        self._warned = len(self.log.warnings)
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


def compile_check(source: str, name: str, *, lua: ModuleType | None = None) -> None:
    """Raise ScriptFailed (``Lua: <file>:<line>: <why>``) when ``source`` does not compile
    (in ``lua``: lupa's Lua 5.3 unless given)."""
    runtime = (lua or stock_lua()).LuaRuntime(register_eval=False, register_builtins=False)
    loaded = runtime.globals().load(source, "@" + name, "t")
    if isinstance(loaded, tuple):
        raise ScriptFailed(f"Lua: {loaded[1]}")
