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
class RecordLayout:
    """One record type: its name, whole length (header included), columns and struct."""

    type: int
    name: str
    length: int
    columns: tuple[str, ...]
    body: struct.Struct | None  # None when the format has an unknown character
    offsets: tuple[int, ...]  # byte offset of each column in the record (header included)
    codes: tuple[str, ...] = ()  # struct code of each column

    def index(self, column: str) -> int | None:
        try:
            return self.columns.index(column)
        except ValueError:
            return None


def parse_fmt(record: bytes | mmap.mmap, offset: int = 0) -> RecordLayout | None:
    """The layout an FMT record at ``offset`` defines (None when the record is nonsense)."""
    kind, length, name, fmt, columns = FMT_BODY.unpack_from(record, offset + 3)
    return make_layout(kind, length, _text(name), _text(fmt), _text(columns))


def make_layout(kind: int, length: int, name: str, fmt: str, columns: str) -> RecordLayout | None:
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
            return RecordLayout(kind, name, length, names, None, ())
        codes.append(code)
        offsets.append(size)
        size += struct.calcsize("<" + code)
    if size != length or (names and len(names) != len(fmt)):
        return None
    body = struct.Struct("<" + "".join(codes))
    return RecordLayout(kind, name, length, names, body, tuple(offsets), tuple(codes))


def _text(raw: bytes) -> str:
    return raw.split(b"\0", 1)[0].decode("ascii", "replace")


@dataclass(slots=True)
class CanColumns:
    """Where a CANF / CAFD layout keeps what a frame needs."""

    fields: struct.Struct  # TimeUS, [Bus,] Id, DLC, read in one call, in record order
    order: tuple[int, ...] | None  # puts them into that order when the record has another
    has_bus: bool
    data_at: int  # offset of the first data byte in the record
    fd: bool  # CAFD: DLC is a CAN FD length code, eight 8-byte data words


def can_columns(layout: RecordLayout) -> CanColumns | str | None:
    """The CAN columns of a CANF / CAFD layout (ArduPilot's or a Lua script's).

    None for any other record type; a reason in words for a CANF / CAFD layout whose
    columns are not understood (its records cannot be read).
    """
    if layout.name not in ("CANF", "CAFD"):
        return None
    if layout.body is None:
        return "its format has a character AP_Logger does not define"
    fd = layout.name == "CAFD"
    wanted = [c for c in ("TimeUS", "Bus", "Id", "DLC") if c in layout.columns]
    missing = {"TimeUS", "Id", "DLC"} - set(wanted)
    if missing:
        return f"it has no {', '.join(sorted(missing))} column"
    prefix, code, width = ("D", "Q", 8) if fd else ("B", "B", 1)
    data = [layout.index(f"{prefix}{k}") for k in range(8)]
    first = data[0]
    if first is None or any(
        i is None
        or layout.codes[i] != code
        or layout.offsets[i] != layout.offsets[first] + k * width
        for k, i in enumerate(data)
    ):
        return f"its data columns are not {prefix}0..{prefix}7 of type {code!r} in a row"
    indexes = [layout.columns.index(c) for c in wanted]
    by_offset = sorted(indexes, key=lambda i: layout.offsets[i])
    fmt, at = "<", 3
    for i in by_offset:
        fmt += "x" * (layout.offsets[i] - at) + layout.codes[i]
        at = layout.offsets[i] + struct.calcsize("<" + layout.codes[i])
    order = None if by_offset == indexes else tuple(by_offset.index(i) for i in indexes)
    return CanColumns(struct.Struct(fmt), order, "Bus" in wanted, layout.offsets[first], fd)


FMT_LAYOUT = make_layout(FMT_TYPE, FMT_LENGTH, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns")
