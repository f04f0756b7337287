"""One candump text line of any layout, parsed with care and explained when it is no frame."""

from __future__ import annotations

import datetime
from binascii import unhexlify
from collections.abc import Callable

from analyzer.protocol.types import CanFrame

CAN_ERR_FLAG = 0x20000000
CAN_EFF_MASK = 0x1FFFFFFF
MAX_CLASSIC_HEX = 16  # 8 data bytes
MAX_FD_HEX = 128  # 64 data bytes
RELATIVE_LIMIT = 1e8  # a screen time below this is no date: -tz or -td
DIRECTIONS = {b"R": "rx", b"r": "rx", b"T": "tx", b"t": "tx"}
FD_LENGTHS = frozenset((*range(9), 12, 16, 20, 24, 32, 48, 64))
_HEXDIGITS = frozenset(b"0123456789abcdefABCDEF")
_HEX_TEXT = b"0123456789abcdefABCDEF"

# Parsed ID text -> (can_id, extended, is_error, wanted); None marks an invalid ID text.
IdInfo = tuple[int, bool, bool, bool]
IdLookup = Callable[[bytes], IdInfo]  # raises LineError for an invalid ID text
ChannelName = Callable[[bytes], str]


class LineError(ValueError):
    """Why a line is not a CAN frame (becomes the detail of a bad_line diagnostic)."""


def id_info(text: bytes, wanted_ids: frozenset[int] | None) -> IdInfo | None:
    """What an ID text says: 1-3 hex digits a standard ID, 4-8 an extended one."""
    if 0 < len(text) <= 8 and not text.translate(None, _HEX_TEXT):
        value = int(text, 16)
        extended = len(text) > 3
        error = extended and bool(value & CAN_ERR_FLAG)
        can_id = value & CAN_EFF_MASK
        if value <= CAN_EFF_MASK or error:
            wanted = error or wanted_ids is None or can_id in wanted_ids
            return (can_id, extended, error, wanted)
    return None


def parse_log_line(line: bytes, frame_id: IdLookup, channel: ChannelName) -> CanFrame:
    """A stripped ``candump -L`` line -> its frame; LineError says what is wrong."""
    close = line.find(b")")
    if close < 0:
        raise LineError("timestamp not closed by ')'")
    ts = timestamp(line[1:close])
    parts = line[close + 1 :].split()
    if len(parts) < 2:
        raise LineError("expected '(time) channel id#data'")
    if len(parts) > 3 or (len(parts) == 3 and parts[2] not in DIRECTIONS):
        raise LineError("unexpected text after the frame")
    frame = parts[1]
    h = frame.find(b"#")
    if h < 0:
        raise LineError("no '#' between CAN ID and data")
    info = frame_id(frame[:h])
    payload, is_fd, is_remote = log_payload(frame[h + 1 :])
    direction = DIRECTIONS[parts[2]] if len(parts) == 3 else ""
    return CanFrame(
        ts,
        info[0],
        payload,
        info[1],
        channel(parts[0]),
        is_remote,
        info[2],
        is_fd,
        direction,
        remote_dlc(frame[h + 1 :]) if is_remote else 0,
    )


def parse_screen_line(
    line: bytes,
    frame_id: IdLookup,
    channel: ChannelName,
    clock: Callable[[], float] | None,
) -> tuple[CanFrame, bool, bool]:
    """The default ``candump`` output: ``[(time)] can0 [RX - -] 123 [8] 11 22 ...``.

    Returns the frame, whether its time is known (from the line or the clock) and
    whether that time is a relative one (-tz or -td: no date).
    """
    tokens = line.split()
    ts, i, dated = _screen_time(tokens)
    if len(tokens) < i + 3:
        raise LineError("not a candump line")
    name = tokens[i]
    i += 1
    direction = ""
    if tokens[i] in (b"RX", b"TX"):
        direction = tokens[i].decode().lower()
        i += 1
        flags = 0
        while i < len(tokens) and flags < 2 and tokens[i] in (b"-", b"B", b"E"):
            i += 1
            flags += 1
    if len(tokens) < i + 2:
        raise LineError("not a candump line")
    info = frame_id(tokens[i])
    length, is_fd = _screen_length(tokens[i + 1])
    payload, is_remote, rest = _screen_data(tokens[i + 2 :], length)
    is_error = info[2]
    if rest[:1] == [b"ERRORFRAME"]:
        is_error = True
        rest = rest[1:]
    if rest and not rest[0].startswith(b"'"):  # ``-a`` appends the data as ASCII in quotes
        raise LineError("unexpected text after the data")
    timed = ts is not None or clock is not None
    when = ts if ts is not None else (clock() if clock is not None else 0.0)
    relative = ts is not None and not dated and 0 <= ts < RELATIVE_LIMIT
    frame = CanFrame(
        when,
        info[0],
        payload,
        info[1],
        channel(name),
        is_remote,
        is_error,
        is_fd,
        direction,
        length if is_remote else 0,
    )
    return frame, timed, relative


def _screen_time(tokens: list[bytes]) -> tuple[float | None, int, bool]:
    """A screen line's time in parentheses, if any: the time, the tokens it took and
    whether it was a date and time of day (``-t A``)."""
    if tokens[0][:1] != b"(":
        return None, 0, False
    if tokens[0].endswith(b")"):
        return timestamp(tokens[0][1:-1]), 1, False
    if len(tokens) > 1 and tokens[1].endswith(b")"):
        return date_time(tokens[0][1:] + b" " + tokens[1][:-1]), 2, True
    raise LineError("timestamp not closed by ')'")


def _screen_length(text: bytes) -> tuple[int, bool]:
    """``[8]`` (or ``[64]``, two digits for CAN FD): the data length, and whether FD."""
    if not (text[:1] == b"[" and text[-1:] == b"]"):
        raise LineError("no data length in brackets after the CAN ID")
    inner = text[1:-1]
    if not inner.isdigit():
        raise LineError("data length is not a number")
    length = int(inner)
    is_fd = len(inner) == 2  # candump prints CAN FD lengths with two digits
    check_length(length, is_fd)
    return length, is_fd


def _screen_data(rest: list[bytes], length: int) -> tuple[bytes, bool, list[bytes]]:
    """The data bytes in hex (or ``remote request``): the payload, whether a remote
    request, and the tokens after them."""
    if rest[:2] == [b"remote", b"request"]:
        return b"", True, rest[2:]
    hex_bytes = rest[:length]
    if len(hex_bytes) < length or not all(
        len(t) == 2 and t[0] in _HEXDIGITS and t[1] in _HEXDIGITS for t in hex_bytes
    ):
        raise LineError(f"expected {length} data bytes in hex")
    return bytes(int(t, 16) for t in hex_bytes), False, rest[length:]


def check_length(length: int, is_fd: bool) -> None:
    """One rule for both layouts: classic frames hold 0..8 bytes, CAN FD the DLC lengths."""
    if not is_fd and length > 8:
        raise LineError(f"data length {length} too large for a classic CAN frame (at most 8)")
    if is_fd and length not in FD_LENGTHS:
        raise LineError(f"{length} data bytes is no CAN FD length (0..8, 12, 16, ..., 64)")


def timestamp(text: bytes) -> float:
    try:
        value = float(text)
    except ValueError:
        raise LineError("bad timestamp") from None
    if not -1e15 < value < 1e15:
        raise LineError("bad timestamp")
    return value


def date_time(text: bytes) -> float:
    """``candump -t A`` times: ``2015-07-10 08:17:32.249713`` in local time."""
    try:
        return datetime.datetime.strptime(text.decode("ascii"), "%Y-%m-%d %H:%M:%S.%f").timestamp()
    except (ValueError, UnicodeDecodeError, OverflowError, OSError):
        raise LineError("bad date/time stamp") from None


def hex_data(text: bytes, limit: int, what: str) -> bytes:
    if len(text) > limit:
        raise LineError(f"{what}: more than {limit // 2} data bytes")
    if len(text) & 1:
        raise LineError(f"{what}: odd number of hex digits")
    if not all(c in _HEXDIGITS for c in text):
        raise LineError(f"{what}: data is not hex")
    return unhexlify(text)


def log_payload(data: bytes) -> tuple[bytes, bool, bool]:
    """The text after ``id#`` -> (data, is_fd, is_remote); LineError says what is wrong."""
    if data[:1] == b"#":  # CAN FD: ##<flags><data>
        if data[1:2] == b"#":
            raise LineError("CAN XL frames are not supported")
        if len(data) < 2 or data[1] not in _HEXDIGITS:
            raise LineError("CAN FD frame without its flags digit")
        payload = hex_data(data[2:], MAX_FD_HEX, "CAN FD frame")
        check_length(len(payload), True)
        return payload, True, False
    if data[:1] in (b"R", b"r"):  # remote request, optionally with its DLC: R, R5, R5_9
        rest = data[1:].split(b"_", 1)[0]
        if rest and not (len(rest) == 1 and rest in b"012345678"):
            raise LineError("bad DLC of a remote frame")
        return b"", False, True
    under = data.find(b"_")  # len8_dlc: 8 data bytes and a DLC 9..F, e.g. 1122334455667788_C
    if under >= 0:
        dlc = data[under + 1 :]
        if len(dlc) != 1 or dlc not in b"9ABCDEFabcdef" or under != MAX_CLASSIC_HEX:
            raise LineError("bad DLC suffix")
        data = data[:under]
    return hex_data(data, MAX_CLASSIC_HEX, "CAN frame"), False, False


def remote_dlc(data: bytes) -> int:
    """The DLC a ``-L`` remote frame requests (``R5`` -> 5); a bare ``R`` requests 0."""
    digit = data[1:2]
    return int(digit) if digit.isdigit() else 0
