"""One BLF object read from its bytes: a CAN frame, or why it was skipped (sans-IO).

``read_object`` takes an object whose bytes are all there and gives what python-can's
``BLFReader`` would make of it, as a CanFrame (the same times, IDs, data, flags and
channel numbers, so that both read a file alike), or a ``Skipped`` that says why not:
an object of a kind that carries no CAN frame, or a damaged one (a header version
Vector does not document, an object too short for its kind).
"""

from __future__ import annotations

from dataclasses import dataclass

from analyzer.inputs.blf.layout import (
    BASE_HEADER,
    CAN_ERROR,
    CAN_ERROR_DATA,
    CAN_ERROR_EXT,
    CAN_ERROR_EXT_DATA,
    CAN_FD_64_DATA,
    CAN_FD_DATA,
    CAN_FD_ERROR_64,
    CAN_FD_ERROR_64_DATA,
    CAN_FD_LENGTHS,
    CAN_FD_MESSAGE,
    CAN_FD_MESSAGE_64,
    CAN_MESSAGE_DATA,
    CAN_MESSAGES,
    EXTENDED_ID,
    FD_64_FD,
    FD_64_REMOTE,
    HEADER_SIZES,
    LOG_CONTAINER,
    OBJECT_HEADER,
    OBJECT_HEADER_2,
    REMOTE,
    TRANSMITTED,
    kind_of,
    stamp_seconds,
)
from analyzer.protocol.types import CanFrame

_ID_MASK = 0x1FFFFFFF
_FD_DATA_MASK = 0x1


@dataclass(frozen=True, slots=True)
class Skipped:
    """An object read past: ``kind`` names what it holds; ``damage`` says what is wrong
    with it (None: a well-formed object that carries no CAN frame)."""

    kind: str
    damage: str | None = None


def header_problem(header_size: int, version: int, size: int) -> str | None:
    """What is wrong with an object's base header (None: nothing)."""
    least = HEADER_SIZES.get(version)
    if least is None:
        return f"header version {version}, which Vector does not document"
    if header_size < least:
        return f"a header of {header_size} bytes, too short for header version {version}"
    if size < header_size:
        return f"a size of {size} bytes, less than its own header ({header_size})"
    return None


# The most an object of each CAN kind holds after its header: its documented fields, with
# 8 bytes to spare for the fields a later version appends (CAN_MESSAGE2 is CAN_MESSAGE
# and 8 more bytes). A CAN FD message of 64 bytes may carry extended data besides.
_SPARE = 8
_MOST_ROOM = {
    **dict.fromkeys(CAN_MESSAGES, CAN_MESSAGE_DATA.size + _SPARE),
    CAN_FD_MESSAGE: CAN_FD_DATA.size + _SPARE,
    CAN_FD_MESSAGE_64: CAN_FD_64_DATA.size + 64 + 64 + _SPARE,
    CAN_ERROR_EXT: CAN_ERROR_EXT_DATA.size + _SPARE,
    CAN_ERROR: CAN_ERROR_DATA.size + _SPARE,
    CAN_FD_ERROR_64: CAN_FD_64_DATA.size + 64 + 64 + _SPARE,
}


def size_problem(kind: int, header_size: int, size: int) -> str | None:
    """An object of a CAN kind longer than that kind can be: its size field is damaged
    (read as it says, it would swallow the objects after it). None: nothing wrong."""
    most = _MOST_ROOM.get(kind)
    if most is None or size - header_size <= most:
        return None
    return f"a size of {size:,} bytes, more than a {kind_of(kind)[:-1]} can hold"


def read_object(data: bytes, at: int, start_time: float) -> CanFrame | Skipped:
    """The object at ``data[at:]`` (its size says where it ends; all of it is there)."""
    _, header_size, version, size, kind = BASE_HEADER.unpack_from(data, at)
    problem = header_problem(header_size, version, size)
    if problem:
        return Skipped(kind_of(kind), f"an object of type {kind} with {problem} skipped")
    if version == 2:
        flags, _, _, stamp, _ = OBJECT_HEADER_2.unpack_from(data, at + BASE_HEADER.size)
    else:
        flags, _, _, stamp = OBJECT_HEADER.unpack_from(data, at + BASE_HEADER.size)
    body = at + header_size
    room = size - header_size
    time = stamp_seconds(stamp, flags) + start_time
    if kind in CAN_MESSAGES:
        if room < CAN_MESSAGE_DATA.size:
            return _short("CAN message", room)
        channel, flags, dlc, can_id, payload = CAN_MESSAGE_DATA.unpack_from(data, body)
        return _frame(time, can_id, payload[:dlc], channel, flags & REMOTE, dlc, flags)
    if kind == CAN_FD_MESSAGE:
        if room < CAN_FD_DATA.size:
            return _short("CAN FD message", room)
        channel, flags, dlc, can_id, _, _, fd_flags, valid, payload = CAN_FD_DATA.unpack_from(
            data, body
        )
        length = _fd_length(dlc)
        frame = _frame(time, can_id, payload[:valid], channel, flags & REMOTE, length, flags)
        frame.is_fd = bool(fd_flags & _FD_DATA_MASK)
        return frame
    if kind == CAN_FD_MESSAGE_64:
        return _fd_64(data, body, room, size, header_size, time)
    if kind == CAN_ERROR_EXT:
        if room < CAN_ERROR_EXT_DATA.size:
            return _short("CAN error frame", room)
        fields = CAN_ERROR_EXT_DATA.unpack_from(data, body)
        channel, dlc, can_id, payload = fields[0], fields[5], fields[7], fields[9]
        return CanFrame(
            time,
            can_id & _ID_MASK,
            bytes(payload[:dlc]),
            bool(can_id & EXTENDED_ID),
            str(channel - 1),
            is_error=True,
            direction="rx",
        )
    if kind in (CAN_ERROR, CAN_FD_ERROR_64):  # an error frame without its details
        layout = CAN_ERROR_DATA if kind == CAN_ERROR else CAN_FD_ERROR_64_DATA
        if room < layout.size:
            return _short("CAN error frame", room)
        channel = layout.unpack_from(data, body)[0]
        return CanFrame(time, 0, b"", False, str(channel - 1), is_error=True, direction="rx")
    if kind == LOG_CONTAINER:
        return Skipped("log containers", "a log container inside another skipped")
    return Skipped(kind_of(kind))


def _frame(
    time: float, can_id: int, payload: bytes, channel: int, remote: int, dlc: int, flags: int
) -> CanFrame:
    """A frame of a CAN (FD) message: data, or the requested DLC of a remote frame."""
    return CanFrame(
        time,
        can_id & _ID_MASK,
        b"" if remote else bytes(payload),
        bool(can_id & EXTENDED_ID),
        str(channel - 1),
        bool(remote),
        False,
        False,
        "tx" if flags & TRANSMITTED else "rx",
        dlc if remote else 0,
    )


def _fd_64(
    data: bytes, body: int, room: int, size: int, header_size: int, time: float
) -> CanFrame | Skipped:
    """A CAN_FD_MESSAGE_64: its data follows its fields (or starts at the extended data
    offset); a valid length beyond what the object holds is filled with zeros, as
    CANoe and python-can do."""
    if room < CAN_FD_64_DATA.size:
        return _short("CAN FD message", room)
    fields = CAN_FD_64_DATA.unpack_from(data, body)
    channel, dlc, valid, can_id, fd_flags, direction, extra = (
        fields[0],
        fields[1],
        fields[2],
        fields[4],
        fields[6],
        fields[12],
        fields[13],
    )
    kept = max(0, min(valid, (extra or size) - header_size - CAN_FD_64_DATA.size))
    start = body + CAN_FD_64_DATA.size
    payload = data[start : start + kept].ljust(valid, b"\0")
    remote = fd_flags & FD_64_REMOTE
    frame = _frame(time, can_id, payload, channel, remote, _fd_length(dlc), 1 if direction else 0)
    frame.is_fd = bool(fd_flags & FD_64_FD)
    return frame


def _fd_length(dlc: int) -> int:
    return CAN_FD_LENGTHS[dlc] if dlc <= 15 else 64


def _short(what: str, room: int) -> Skipped:
    return Skipped(
        what + "s", f"an object of {room} bytes after its header skipped: too few for a {what}"
    )
