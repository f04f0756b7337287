"""Strings and numbers as the generated files (Lua, DBC) write them."""

from __future__ import annotations


def lua_string(text: str) -> str:
    """A Lua string literal of ``text``."""
    escaped = text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
    return f'"{escaped}"'


def short_number(value: float) -> str:
    """A number for Lua or DBC: integers without a decimal point, others as short as exact."""
    if float(value).is_integer():
        return str(int(value))
    return repr(float(value))
