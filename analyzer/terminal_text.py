"""Text that came from a file or the wire, made safe to print: control characters escaped."""

from __future__ import annotations

import re

# C0 and C1 control characters, DEL, the line / paragraph separators and the bidirectional
# controls that reorder what follows them on screen. An ESC from a channel name, a metadata
# record or a text message could otherwise retitle, recolour or clear the user's terminal.
_UNSAFE = re.compile("[\x00-\x1f\x7f-\x9f\u061c\u200e\u200f\u2028-\u202e\u2066-\u2069]")
_NAMED = {"\n": "\\n", "\r": "\\r", "\t": "\\t"}


def _escape(match: re.Match[str]) -> str:
    char = match.group()
    named = _NAMED.get(char)
    if named is not None:
        return named
    code = ord(char)
    return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}"


def printable(text: str) -> str:
    """``text`` with every control character written as an escape (``\\x1b``, ``\\n``...),
    so it shows as one inert line; text without any comes back unchanged (same object)."""
    if _UNSAFE.search(text) is None:
        return text
    return _UNSAFE.sub(_escape, text)


def printable_lines(text: str) -> str:
    """Like ``printable`` but keeps the line breaks of a multi-line report."""
    return "\n".join(printable(line) for line in text.split("\n"))
