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
            buf,
            rows,
            starts[rows],
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


def _read_shape(
    buf: Array,
    rows: Array,
    starts: Array,
    length: int,
    close: int,
    hash_at: int,
    id_digits: int,
    direction: bool,
    frames: FrameColumns,
    fast: Array,
    channel_name: Any,
) -> None:
    """Check and read the lines at ``rows`` that all have one shape."""
    data_end = length - 2 if direction else length
    digits = data_end - hash_at - 1
    point = close - 7  # six digits after the point
    space = hash_at - id_digits - 1  # between channel and ID
    stamp_digits = close - 2
    if digits % 2 or digits > 16 or point < 2 or stamp_digits > MAX_STAMP_DIGITS:
        return
    if space <= close + 2:  # no channel name
        return
    lines = _lines(buf, rows, starts, length)
    good = _digits(lines[:, 1:point]) & _digits(lines[:, point + 1 : close])
    good &= lines[:, point] == 46
    good &= (lines[:, close + 1] == 32) & (lines[:, space] == 32)
    good &= (lines[:, close + 2 : space] > 32).all(axis=1)
    good &= _hex(lines[:, space + 1 : hash_at]) & _hex(lines[:, hash_at + 1 : data_end])
    if id_digits == 8:
        good &= lines[:, space + 1] <= ord("1")
    if not good.all():
        rows, lines = rows[good], lines[good]
    if not rows.shape[0]:
        return
    micros = np.zeros(rows.shape[0], np.int64)
    for column in (*range(1, point), *range(point + 1, close)):
        micros *= 10
        micros += lines[:, column] - 48
    times = micros.astype(np.float64)
    exact = times < _BIG
    if not exact.all():
        rows, lines, times = rows[exact], lines[exact], times[exact]
    can_id = np.zeros(rows.shape[0], np.int64)
    for column in range(space + 1, hash_at):
        can_id <<= 4
        can_id |= _nibbles(lines[:, column])
    size = digits // 2
    if size:
        hexes = _nibbles(lines[:, hash_at + 1 : data_end])
        frames.data[rows, :size] = hexes[:, 0::2] << 4 | hexes[:, 1::2]
    frames.time[rows] = times / 1e6
    frames.can_id[rows] = can_id
    frames.extended[rows] = id_digits == 8
    frames.length[rows] = size
    if direction:
        frames.direction[rows] = _DIRECTION[lines[:, length - 1]]
    names = lines[:, close + 2 : space]
    frames.channel[rows] = _channel_numbers(names, frames.channels, channel_name)
    fast[rows] = True


def _lines(buf: Array, rows: Array, starts: Array, length: int) -> Array:
    """The lines at ``rows`` as an (n, length) array: a view when they follow each other."""
    n = rows.shape[0]
    first = int(starts[0])
    if int(rows[-1]) - int(rows[0]) == n - 1 and first + n * (length + 1) <= buf.shape[0]:
        view = np.lib.stride_tricks.as_strided(
            buf[first:], shape=(n, length), strides=(length + 1, 1), writeable=False
        )
        return view
    return buf[starts[:, None] + np.arange(length)]


def _digits(part: Array) -> Array:
    return ((part - 48) <= 9).all(axis=1)


def _hex(part: Array) -> Array:
    return (((part - 48) <= 9) | (((part | 32) - 97) <= 5)).all(axis=1)


def _nibbles(part: Array) -> Array:
    """Hex digits (already checked) as their values."""
    return (part & 15) + 9 * (part >> 6)


def _channel_numbers(names: Array, channels: list[str], channel_name: Any) -> Array | int:
    """Each row's channel as an index into ``channels`` (names added as they come)."""
    first = names[0]
    if (names == first).all():
        return _number(channels, channel_name(first.tobytes()))
    width = names.shape[1]
    keys = np.ascontiguousarray(names).view(f"V{width}").ravel()
    unique, inverse = np.unique(keys, return_inverse=True)
    numbers = np.array([_number(channels, channel_name(u.tobytes())) for u in unique])
    return numbers[inverse.ravel()]


def _number(channels: list[str], name: str) -> int:
    try:
        return channels.index(name)
    except ValueError:
        channels.append(name)
        return len(channels) - 1
