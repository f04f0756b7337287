"""How an emulated ArduPilot binding is declared, called from Lua and checked like ArduPilot's."""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar, TypeVar

from analyzer.ardupilot.values import UInt32, check_int32, float32, uint32_method

F = TypeVar("F", bound=Callable[..., Any])


@dataclass(frozen=True)
class Signature:
    """A binding as docs.lua declares it: its parameter names, the trailing optional ones,
    whether it may also be called with '.' (ArduPilot's CAN:get_device allows both), and
    the warning of a deprecated one (bindings.desc's ``deprecate``)."""

    params: tuple[str, ...]
    optional: int = 0
    dot_ok: bool = False
    deprecated: str = ""


def method(
    *params: str, optional: int = 0, dot_ok: bool = False, deprecated: str = ""
) -> Callable[[F], F]:
    """Mark a Python method as a binding with docs.lua's parameter names."""

    def mark(fn: F) -> F:
        signature = Signature(params, optional, dot_ok, deprecated)
        fn.lua_signature = signature  # type: ignore[attr-defined]
        return fn

    return mark


class CallLog:
    """Every binding the script called: (class, name, arguments without self) -> count;
    ``warnings``: ArduPilot's warning for the first call of each deprecated binding."""

    def __init__(self) -> None:
        self.calls: Counter[tuple[str, str, int]] = Counter()
        self.warnings: list[str] = []


class Binding:
    """An object ArduPilot hands a script (a singleton like ``mount`` or a userdata like a
    CANFrame). ``lua_class`` is its docs.lua class name; its methods marked with
    ``@method`` are all Lua can reach, called with ':' and exactly their arguments."""

    lua_class: ClassVar[str] = ""
    lua_constants: ClassVar[dict[str, int]] = {}

    @classmethod
    def signatures(cls) -> dict[str, Signature]:
        out: dict[str, Signature] = {}
        for name in dir(cls):
            signature = getattr(getattr(cls, name, None), "lua_signature", None)
            if isinstance(signature, Signature):
                out[name] = signature
        return out


class LuaCall:
    """A binding as Lua sees it: checks the call like ArduPilot's generated code (self,
    argument count, 32-bit integers) and gives floats back as 32-bit floats."""

    def __init__(
        self, owner: Binding | None, name: str, fn: Callable[..., Any], log: CallLog
    ) -> None:
        self.owner = owner
        self.name = name
        self.fn = fn
        self.log = log
        self.signature: Signature = fn.lua_signature  # type: ignore[attr-defined]

    @property
    def where(self) -> str:
        if self.owner is None:
            return self.name
        return f"{self.owner.lua_class}:{self.name}"

    def __call__(self, *args: Any) -> Any:
        from analyzer.ardupilot.values import ScriptError

        signature = self.signature
        if self.owner is not None:
            if args and args[0] is self.owner:
                args = args[1:]
            elif not signature.dot_ok:
                raise ScriptError(f"{self.where}: called without its object (use ':')")
        most = len(signature.params)
        if not most - signature.optional <= len(args) <= most:
            wanted = str(most) if not signature.optional else f"{most - signature.optional}-{most}"
            raise ScriptError(f"{self.where}: got {len(args)} arguments, expected {wanted}")
        for arg in args:
            check_int32(arg, self.where)
        if signature.deprecated:
            warning = f"{self.where} {signature.deprecated}"  # once, as ArduPilot warns
            if warning not in self.log.warnings:
                self.log.warnings.append(warning)
        self.log.calls[(self.owner.lua_class if self.owner else "", self.name, len(args))] += 1
        return _to_lua(self.fn(*args))


def _to_lua(value: Any) -> Any:
    if isinstance(value, float):
        return float32(value)
    if isinstance(value, tuple):
        return tuple(_to_lua(v) for v in value)
    return value


def global_call(name: str, fn: Callable[..., Any], log: CallLog) -> LuaCall:
    """A global function (millis, uint32_t, CANFrame, Parameter) as Lua calls it."""
    return LuaCall(None, name, fn, log)


def attribute_getter(log: CallLog) -> Callable[[Any, Any], Any]:
    """lupa's attribute handler: what ``obj.name`` gives in Lua for a Python object.

    Only the declared bindings (and constants) are reachable; anything else is nil, as a
    userdata's missing method is in ArduPilot."""

    def get(obj: Any, name: Any) -> Any:
        if not isinstance(name, str):
            return None
        if isinstance(obj, UInt32):
            fn = uint32_method(obj, name)
            if fn is None:
                return None
            fn.lua_signature = Signature(())  # type: ignore[attr-defined]
            call = LuaCall(None, name, fn, log)
            return _UInt32Call(obj, call)
        if isinstance(obj, Binding):
            if name in obj.lua_constants:
                return obj.lua_constants[name]
            fn = getattr(obj, name, None)
            if fn is not None and isinstance(getattr(fn, "lua_signature", None), Signature):
                return LuaCall(obj, name, fn, log)
        return None

    return get


class _UInt32Call:
    """uint32_t:toint() / :tofloat(), called with ':' on the value."""

    def __init__(self, value: UInt32, call: LuaCall) -> None:
        self.value = value
        self.call = call

    def __call__(self, *args: Any) -> Any:
        from analyzer.ardupilot.values import ScriptError

        if not args or args[0] is not self.value:
            raise ScriptError(f"uint32_t:{self.call.name}: called without its object (use ':')")
        if len(args) != 1:
            raise ScriptError(f"uint32_t:{self.call.name}: got {len(args)} arguments, expected 1")
        self.call.log.calls[("uint32_t_ud", self.call.name, 0)] += 1
        return _to_lua(self.call.fn())


def attribute_setter(obj: Any, name: Any, value: Any) -> None:
    """Lua may not write into a binding (ArduPilot's userdata are not tables)."""
    from analyzer.ardupilot.values import ScriptError

    raise ScriptError(f"attempt to set field {name!r} of a userdata")
