"""The record formats of an ArduPilot DataFlash log: FMT records made into precompiled structs.

Every record is ``A3 95 <type>`` and a body laid out as the FMT record for that type
says: a format string of one character per column (AP_Logger's LogStructure.h) and
the column names. ``Layout`` keeps the struct and where the columns a reader needs
start, so the reader never looks a column up by name per record.
"""

from __future__ import annotations

import mmap
import struct
from dataclasses import dataclass

HEAD = b"\xa3\x95"
FMT_TYPE = 0x80
FMT_LENGTH = 89  # 3 header bytes + Type, Length, Name[4], Format[16], Columns[64]
FMT_BODY = struct.Struct("<BB4s16s64s")

# Format characters of AP_Logger -> struct codes (as pymavlink's DFReader reads them).
STRUCT_CODES = {
    "a": "64s",  # int16_t[32]
    "b": "b",
    "B": "B",
    "g": "e",
    "h": "h",
    "H": "H",
    "i": "i",
    "I": "I",
    "f": "f",
    "d": "d",
    "n": "4s",
    "N": "16s",
    "Z": "64s",
    "c": "h",
    "C": "H",
    "e": "i",
    "E": "I",
    "L": "i",
    "M": "B",
    "q": "q",
    "Q": "Q",
}


@dataclass(slots=True)
class Layout:
    """One record type: its name, whole length (header included), columns and struct."""

    type: int
    name: str
    length: int
    columns: tuple[str, ...]
    body: struct.Struct | None  # None when the format has an unknown character
    offsets: tuple[int, ...]  # byte offset of each column in the record (header included)

    def index(self, column: str) -> int | None:
        try:
            return self.columns.index(column)
        except ValueError:
            return None


def parse_fmt(record: bytes | mmap.mmap, offset: int = 0) -> Layout | None:
    """The layout an FMT record at ``offset`` defines (None when the record is nonsense)."""
    kind, length, name, fmt, columns = FMT_BODY.unpack_from(record, offset + 3)
    return make_layout(kind, length, _text(name), _text(fmt), _text(columns))


def make_layout(kind: int, length: int, name: str, fmt: str, columns: str) -> Layout | None:
    """A Layout from the fields of an FMT record; None when they contradict each other."""
    names = tuple(columns.split(",")) if columns else ()
    if length < 3 or not name:
        return None
    codes = []
    offsets = []
    size = 3
    for char in fmt:
        code = STRUCT_CODES.get(char)
        if code is None:
            return Layout(kind, name, length, names, None, ())
        codes.append(code)
        offsets.append(size)
        size += struct.calcsize("<" + code)
    if size != length or (names and len(names) != len(fmt)):
        return None
    return Layout(kind, name, length, names, struct.Struct("<" + "".join(codes)), tuple(offsets))


def _text(raw: bytes) -> str:
    return raw.split(b"\0", 1)[0].decode("ascii", "replace")


FMT_LAYOUT = make_layout(FMT_TYPE, FMT_LENGTH, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns")
