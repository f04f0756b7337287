"""ArduPilot's Lua values: 32-bit integers and floats, uint32_t, and binding argument checks."""

from __future__ import annotations

import math
import struct
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1
UINT32_MASK = 0xFFFFFFFF
_FLOAT = struct.Struct("<f")


class ScriptError(Exception):
    """An error ArduPilot raises in the script (a wrong argument, a value out of range)."""


def float32(value: float) -> float:
    """A float as ArduPilot's Lua holds it: a 32-bit float (LUA_32BITS)."""
    result: float = _FLOAT.unpack(_FLOAT.pack(value))[0]
    return result


def int32(value: int) -> int:
    """An integer as a 32-bit lua_Integer holds it (C's wrap of a wider value)."""
    value &= UINT32_MASK
    return value - 2**32 if value > INT32_MAX else value


def check_int32(value: Any, where: str) -> None:
    """An integer handed to a binding must fit ArduPilot's 32-bit lua_Integer: a wider one
    is a value this Lua 5.3 (64-bit integers) computed and ArduPilot's would not have."""
    wide = isinstance(value, int) and not INT32_MIN <= value <= INT32_MAX
    if wide and not isinstance(value, bool):
        raise ScriptError(f"{where}: integer {value} does not fit a 32-bit Lua integer")


def to_integer(value: Any, where: str) -> int:
    """luaL_checkinteger: an integer, or a float with an exact integer value."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ScriptError(f"{where}: number expected, got {lua_type(value)}")
    if isinstance(value, float):
        if not math.isfinite(value) or not value.is_integer():
            raise ScriptError(f"{where}: number has no integer representation")
        value = int(value)
    check_int32(value, where)
    return value


def to_number(value: Any, where: str) -> float:
    """luaL_checknumber: an integer or a float (as a float)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ScriptError(f"{where}: number expected, got {lua_type(value)}")
    check_int32(value, where)
    return float(value)


def lua_type(value: Any) -> str:
    if value is None:
        return "nil"
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, (int, float)):
        return "number"
    if isinstance(value, (str, bytes)):
        return "string"
    return "userdata"


def coerce_uint32(value: Any, where: str) -> int:
    """ArduPilot's coerce_to_uint32_t: a uint32_t, an integer, or a float in range."""
    if isinstance(value, UInt32):
        return value.value
    if isinstance(value, int) and not isinstance(value, bool):
        check_int32(value, where)
        return value & UINT32_MASK
    if isinstance(value, float) and 0 <= value <= UINT32_MASK:
        return int(value)
    raise ScriptError(f"{where}: Unable to coerce to uint32_t")


@dataclass(frozen=True)
class UInt32:
    """ArduPilot's uint32_t userdata: arithmetic modulo 2^32 with integers mixed in."""

    value: int

    def __post_init__(self) -> None:
        object.__setattr__(self, "value", self.value & UINT32_MASK)

    def __str__(self) -> str:
        return str(self.value)


def uint32_method(obj: UInt32, name: str) -> Callable[..., Any] | None:
    """The methods of a uint32_t: toint (a 32-bit integer, wrapped) and tofloat."""
    if name == "toint":
        return lambda: int32(obj.value)
    if name == "tofloat":
        return lambda: float32(float(obj.value))
    return None


_ARITHMETIC: dict[str, Callable[[int, int], int]] = {
    "__add": lambda a, b: a + b,
    "__sub": lambda a, b: a - b,
    "__mul": lambda a, b: a * b,
    "__div": lambda a, b: a // b,
    "__idiv": lambda a, b: a // b,
    "__mod": lambda a, b: a % b,
    "__band": lambda a, b: a & b,
    "__bor": lambda a, b: a | b,
    "__bxor": lambda a, b: a ^ b,
    "__shl": lambda a, b: a << b if b < 32 else 0,
    "__shr": lambda a, b: a >> b if b < 32 else 0,
}
_COMPARISON: dict[str, Callable[[int, int], bool]] = {
    "__eq": lambda a, b: a == b,
    "__lt": lambda a, b: a < b,
    "__le": lambda a, b: a <= b,
}


def uint32_metamethods() -> dict[str, Callable[..., Any]]:
    """The uint32_t operators, as functions of two Lua values (one of them a uint32_t)."""

    def arithmetic(name: str, op: Callable[[int, int], int]) -> Callable[[Any, Any], UInt32]:
        def run(a: Any, b: Any) -> UInt32:
            if not isinstance(a, UInt32) and not isinstance(b, UInt32):
                raise ScriptError("attempt to perform arithmetic on a userdata value")
            x, y = coerce_uint32(a, name), coerce_uint32(b, name)
            if name in ("__div", "__idiv", "__mod") and y == 0:
                raise ScriptError(f"uint32_t {name[2:]}: division by zero")
            return UInt32(op(x, y))

        return run

    def comparison(name: str, op: Callable[[int, int], bool]) -> Callable[[Any, Any], bool]:
        def run(a: Any, b: Any) -> bool:
            if not isinstance(a, UInt32) and not isinstance(b, UInt32):
                if name == "__eq":
                    return a is b
                raise ScriptError("attempt to compare two userdata values")
            return op(coerce_uint32(a, name), coerce_uint32(b, name))

        return run

    out: dict[str, Callable[..., Any]] = {
        name: arithmetic(name, op) for name, op in _ARITHMETIC.items()
    }
    out.update({name: comparison(name, op) for name, op in _COMPARISON.items()})
    out["__bnot"] = lambda a, _b=None: UInt32(~coerce_uint32(a, "__bnot"))
    out["__unm"] = lambda a, _b=None: UInt32(-coerce_uint32(a, "__unm"))
    return out
