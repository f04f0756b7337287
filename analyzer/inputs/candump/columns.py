"""Well-formed ``candump -L`` lines of a block read as arrays, with numpy, in a few passes.

A block's lines are told apart by their shape: where the ``)`` and the ``#`` are, how
long the line is, whether the CAN ID has 3 or 8 digits and whether a direction letter
follows the data. Lines of one shape have every part in the same columns, so each shape
is checked and read as one 2-D array: every byte's class against what its column must
hold (a digit, the point, hex, a space, no white space in the channel name), then the
time, ID and data bytes converted column by column. A line is taken only when it is
exactly what the line parser would read the same way (6 digits after the point, 3 or 8
ID digits, an even number of data digits up to 16, single spaces); any other line, and
the lines of rare shapes, go to the line parser (``LineTable.fast`` is False for them),
which says what is wrong with them. ``tests/test_columnar_decode.py`` holds the two to
the same results.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from analyzer.protocol.frame_columns import FrameColumns

Array = npt.NDArray[Any]

WIDTH = 80  # longer lines go to the line parser (a classic -L line is about 50 bytes)
MAX_SHAPES = 24  # shapes read as arrays in one block; lines of further ones go line by line
MAX_STAMP_DIGITS = 18  # digits of a stamp read as one int64 (and exact as a float: < 2**53)

_DIRECTION = np.zeros(256, np.int8)  # DIRECTIONS index of a direction letter
_DIRECTION[[ord("R"), ord("r")]] = 1
_DIRECTION[[ord("T"), ord("t")]] = 2
_IS_DIRECTION = np.zeros(256, bool)
_IS_DIRECTION[[ord(c) for c in "RrTt"]] = True
_BIG = float(2**53)


@dataclass(slots=True)
class LineTable:
    """The lines of a block: where each starts and ends, and those read as frames.

    ``fast[i]`` says that line ``i`` was read into row ``i`` of ``frames`` (the other
    rows hold nothing of use)."""

    starts: Array
    ends: Array
    fast: Array
    frames: FrameColumns


def read_lines(block: bytes, channel_name: Any) -> LineTable:
    """Every line of ``block`` (whole lines, each ending with ``\\n``) that is a plain
    ``candump -L`` frame, as columns; ``channel_name`` makes a channel's name of its bytes."""
    buf = np.frombuffer(block, np.uint8)
    ends = np.flatnonzero(buf == 10)
    n = ends.shape[0]
    starts = np.empty(n, np.int64)
    if n:
        starts[0] = 0
        starts[1:] = ends[:-1] + 1
    lengths = ends - starts
    close, closes = _only(buf == 41, ends, n)  # ')'
    hashes, hash_count = _only(buf == 35, ends, n)  # '#'
    c = close - starts
    h = hashes - starts
    ok = (closes == 1) & (hash_count == 1) & (lengths <= WIDTH) & (lengths > 0)
    ok &= (buf[starts] == 40) & (c >= 9) & (h > c + 6)
    last = buf[np.maximum(ends - 1, 0)]
    before = buf[np.maximum(ends - 2, 0)]
    direction = (before == 32) & _IS_DIRECTION[last]
    short_id = buf[np.maximum(hashes - 4, 0)] == 32
    long_id = ~short_id & (buf[np.maximum(hashes - 9, 0)] == 32)
    ok &= short_id | long_id
    key = ((lengths * WIDTH + c) * WIDTH + h) * 4 + long_id * 2 + direction
    frames = _blank(n)
    fast = np.zeros(n, bool)
    lines = Lines(block, starts, lengths + 1)
    todo = np.flatnonzero(ok)
    keys = key[todo]
    shapes = 0
    while todo.shape[0] and shapes < MAX_SHAPES:
        same = keys == keys[0]
        rows = todo[same]
        todo, keys = todo[~same], keys[~same]
        shapes += 1
        i = int(rows[0])
        _read_shape(
            lines,
            rows,
            int(lengths[i]),
            int(c[i]),
            int(h[i]),
            8 if long_id[i] else 3,
            bool(direction[i]),
            frames,
            fast,
            channel_name,
        )
    return LineTable(starts, ends, fast, frames)


def _only(mask: Array, ends: Array, n: int) -> tuple[Array, Array]:
    """Where the one marked byte of each line is, and how many each line has."""
    where = np.flatnonzero(mask)
    line = np.searchsorted(ends, where)
    count = np.bincount(line, minlength=n)[:n]
    position = np.zeros(n, np.int64)
    position[line] = where  # lines with more than one are not taken anyway
    return position, count


def _blank(n: int) -> FrameColumns:
    return FrameColumns(
        np.zeros(n, np.float64),
        np.zeros(n, np.int64),
        np.zeros(n, bool),
        np.zeros(n, np.uint8),
        np.zeros((n, 8), np.uint8),
        np.zeros(n, np.int32),
        [],
        np.zeros(n, np.int8),
    )


def _timestamps(at: Any, point: int, whole: int, good: Array) -> Array:
    """The lines' ``(seconds.micros)`` stamps as whole microseconds (uint64); ``good`` is
    narrowed to the lines whose stamp is all digits."""
    fraction = at.right(point + 1, 6)
    good &= _all_digits(fraction)
    micros = _decimal(fraction)
    high = max(0, whole - 8)
    low = at.right(1 + high, whole - high)
    good &= _all_digits(low)
    seconds = _decimal(low)
    if high:
        top = at.right(1, high)
        good &= _all_digits(top)
        seconds += _decimal(top) * np.uint64(10**8)
    micros += seconds * np.uint64(10**6)
    return micros


def _can_ids(at: Any, space: int, id_digits: int, good: Array) -> Array:
    """The lines' CAN IDs (3 or 8 hex digits after ``space``); ``good`` is narrowed to
    the lines whose ID is hex (and, extended, at most 29 bits)."""
    ident = at.left(space + 1, id_digits)
    good &= _all_hex(ident)
    if id_digits == 8:
        good &= at.byte(space + 1) <= ord("1")
        can_id = _pack(_nibbles(ident))
        return (
            (can_id & 0xFF) << 24
            | (can_id >> 8 & 0xFF) << 16
            | (can_id >> 16 & 0xFF) << 8
            | (can_id >> 24)
        )
    nib = _nibbles(ident)
    return (nib & 0xF) << 8 | (nib >> 8 & 0xF) << 4 | (nib >> 16 & 0xF)


def _read_shape(
    lines: Lines,
    rows: Array,
    length: int,
    close: int,
    hash_at: int,
    id_digits: int,
    direction: bool,
    frames: FrameColumns,
    fast: Array,
    channel_name: Any,
) -> None:
    """Check and read the lines at ``rows`` that all have one shape, 8 bytes at a time
    (each 8-byte word of a line as one uint64: SWAR, SIMD within a register)."""
    data_end = length - 2 if direction else length
    digits = data_end - hash_at - 1
    point = close - 7  # six digits after the point
    space = hash_at - id_digits - 1  # between channel and ID
    whole = point - 1  # digits before the point
    if digits % 2 or digits > 16 or whole < 1 or close - 2 > MAX_STAMP_DIGITS:
        return
    if space <= close + 2:  # no channel name
        return
    at = lines.at(rows)
    good = (at.byte(point) == 46) & (at.byte(close + 1) == 32) & (at.byte(space) == 32)
    micros = _timestamps(at, point, whole, good)
    channel = [at.left(c, min(8, space - c), 0x21) for c in range(close + 2, space, 8)]
    for word in channel:
        good &= _all_solid(word)
    can_id = _can_ids(at, space, id_digits, good)
    data = np.zeros(rows.shape[0], np.uint64)
    for half in range(0, digits, 8):
        word = at.left(hash_at + 1 + half, min(8, digits - half))
        good &= _all_hex(word)
        data |= _pack(_nibbles(word)) << np.uint64(4 * half)
    times = micros.astype(np.float64)
    good &= times < _BIG
    if not good.all():
        rows, times, can_id, data = rows[good], times[good], can_id[good], data[good]
        channel = [word[good] for word in channel]
        at = lines.at(rows)
    if not rows.shape[0]:
        return
    frames.time[rows] = times / 1e6
    frames.can_id[rows] = can_id.astype(np.int64)
    frames.extended[rows] = id_digits == 8
    frames.length[rows] = digits // 2
    frames.data[rows] = data.view(np.uint8).reshape(-1, 8)
    if direction:
        frames.direction[rows] = _DIRECTION[at.byte(length - 1)]
    frames.channel[rows] = _channel_numbers(
        channel, space - close - 2, frames.channels, channel_name
    )
    fast[rows] = True


_H = np.uint64(0x8080808080808080)
_ONES = 0x0101010101010101


def _u(byte: int) -> np.uint64:
    """``byte`` in every byte of a word."""
    return np.uint64(byte * _ONES)


def _digit_bits(w: Array) -> Array:
    """The top bit of each byte set where that byte is an ASCII digit (for bytes < 0x80)."""
    return ~(w + _u(0x46)) & ((w | _H) - _u(0x30)) & _H


def _all_digits(w: Array) -> Array:
    return (_digit_bits(w) == _H) & ((w & _H) == 0)


def _all_hex(w: Array) -> Array:
    lower = w | _u(0x20)
    letters = ~(lower + _u(0x19)) & ((lower | _H) - _u(0x61)) & _H
    return ((_digit_bits(w) | letters) == _H) & ((w & _H) == 0)


def _all_solid(w: Array) -> Array:
    """Every byte above 0x20 (no white space, no control byte)."""
    return (((w & _u(0x7F)) + _u(0x5F)) | w) & _H == _H


def _decimal(w: Array) -> Array:
    """8 ASCII digits (the first the most significant) as their number."""
    v = w - _u(0x30)
    v = (v * np.uint64(10) + (v >> np.uint64(8))) & np.uint64(0x00FF00FF00FF00FF)
    v = (v * np.uint64(100) + (v >> np.uint64(16))) & np.uint64(0x0000FFFF0000FFFF)
    return (v * np.uint64(10000) + (v >> np.uint64(32))) & np.uint64(0xFFFFFFFF)


def _nibbles(w: Array) -> Array:
    """Each hex digit byte as its value."""
    return (w & _u(0x0F)) + np.uint64(9) * ((w >> np.uint64(6)) & _u(0x01))


def _pack(n: Array) -> Array:
    """8 nibbles (one a byte) as 4 bytes, the first pair in the lowest byte."""
    v = ((n << np.uint64(4)) | (n >> np.uint64(8))) & np.uint64(0x00FF00FF00FF00FF)
    v = (v | (v >> np.uint64(8))) & np.uint64(0x0000FFFF0000FFFF)
    return (v | (v >> np.uint64(16))) & np.uint64(0xFFFFFFFF)


_SPARE = bytearray(16)


class Lines:
    """A block with 8 spare bytes before and after, read 8 bytes at a time (the arrays
    made of it are copies: the buffer is used again for the next block)."""

    def __init__(self, block: bytes, starts: Array, length_plus_one: Array) -> None:
        global _SPARE
        size = len(block) + 16
        if len(_SPARE) < size:  # one buffer, reused: no fresh pages for every block
            _SPARE = bytearray(max(size, 2 * len(_SPARE)))
        _SPARE[8 : 8 + len(block)] = block
        _SPARE[8 + len(block) : size] = bytes(8)
        self.padded = memoryview(_SPARE)[:size]
        self.bytes = np.frombuffer(self.padded, np.uint8)
        self.words = np.ndarray((len(self.padded) - 7, 8), np.uint8, self.padded, 0, (1, 1))
        self.starts = starts + 8
        self.step = length_plus_one

    def at(self, rows: Array) -> Row:
        return Row(self, rows)


class Row:
    """The lines at some rows: bytes and words at a column of each."""

    def __init__(self, lines: Lines, rows: Array) -> None:
        self.lines = lines
        self.offsets = lines.starts[rows]
        n = rows.shape[0]
        step = int(lines.step[rows[0]]) if n else 0
        self.step = step if n and int(self.offsets[-1] - self.offsets[0]) == (n - 1) * step else 0
        self.n = n

    def _load(self, col: int) -> Array:
        first = int(self.offsets[0]) + col if self.n else 0
        if self.step:
            return np.ndarray((self.n,), "<u8", self.lines.padded, first, (self.step,))
        return self.lines.words[self.offsets + col].view("<u8").ravel()

    def byte(self, col: int) -> Array:
        if self.step:
            first = int(self.offsets[0]) + col
            return np.ndarray((self.n,), np.uint8, self.lines.padded, first, (self.step,))
        return self.lines.bytes[self.offsets + col]

    def left(self, col: int, width: int, fill: int = 0x30) -> Array:
        """Bytes ``col`` to ``col + width`` (at most 8) in the low bytes; ``fill`` above."""
        w = self._load(col)
        if width == 8:
            return w
        keep = np.uint64((1 << (8 * width)) - 1)
        return (w & keep) | (_u(fill) & ~keep)

    def right(self, col: int, width: int) -> Array:
        """Bytes ``col`` to ``col + width`` (at most 8) in the high bytes; '0' below."""
        w = self._load(col + width - 8)
        if width == 8:
            return w
        keep = ~np.uint64((1 << (8 * (8 - width))) - 1)
        return (w & keep) | (_u(0x30) & ~keep)


def _channel_numbers(
    words: list[Array], width: int, channels: list[str], channel_name: Any
) -> Array | int:
    """Each row's channel (``width`` bytes in ``words``) as an index into ``channels``
    (names added as they come)."""
    names = np.stack(words, axis=1) if len(words) > 1 else words[0][:, None]
    if (names == names[0]).all():
        return _number(channels, channel_name(_text(names[0], width)))
    unique, inverse = np.unique(names, axis=0, return_inverse=True)
    numbers = np.array([_number(channels, channel_name(_text(u, width))) for u in unique])
    return numbers[inverse.ravel()]


def _text(words: Array, width: int) -> bytes:
    return np.ascontiguousarray(words).astype("<u8").tobytes()[:width]


def _number(channels: list[str], name: str) -> int:
    try:
        return channels.index(name)
    except ValueError:
        channels.append(name)
        return len(channels) - 1
