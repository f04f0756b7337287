"""A run of BLF objects found and read in vectors: where each starts, and CAN messages as columns.

``chain`` finds every ``LOBJ`` signature in the log data at once and follows the
objects from one to the next (each next one starts within 4 bytes after the size the
one before gives, the padding python-can writes and skips), as far as they follow each
other and are whole. ``message_columns`` reads the CAN messages among them as
``FrameColumns``: the same times (a 64-bit time stamp below 2**53 divided once is what
python-can's decimal product gives), IDs, data and channel numbers as ``read_object``
gives one at a time. Everything else (other kinds, remote frames, damage) is left to
``read_object``, in its place.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from analyzer.inputs.base import LATEST_TIME
from analyzer.inputs.blf.layout import (
    BASE_HEADER,
    CAN_MESSAGE_DATA,
    CAN_MESSAGES,
    EXTENDED_ID,
    HEADER_SIZES,
    REMOTE,
    TIME_OFFSET,
    TIME_TEN_MICROS,
    TRANSMITTED,
)
from analyzer.protocol.arrays import distinct
from analyzer.protocol.frame_columns import FrameColumns

Array = npt.NDArray[Any]

_SIGNATURE = int.from_bytes(b"LOBJ", "little")
_PADDING = 4  # the next object starts this far at most after the size the last one gave
_EXACT = 2**53  # time stamps below this are exact as float64
_HEADER = np.dtype(
    {
        "names": ["header_size", "version", "size", "type", "flags", "stamp"],
        "formats": ["<u2", "<u2", "<u4", "<u4", "<u4", "<u8"],
        "offsets": [4, 6, 8, 12, 16, TIME_OFFSET],
        "itemsize": 32,
    }
)
_MESSAGE = np.dtype(
    {
        "names": ["channel", "flags", "dlc", "id", "data"],
        "formats": ["<u2", "u1", "u1", "<u4", ("u1", 8)],
        "offsets": [0, 2, 3, 4, 8],
        "itemsize": CAN_MESSAGE_DATA.size,
    }
)


@dataclass(slots=True)
class Chain:
    """Whole objects that follow each other: their starts and headers; ``end`` is where
    the last of them ends (the next object is looked for from there)."""

    starts: Array
    headers: Array
    end: int


def chain(data: bytes, start: int, limit: int) -> Chain | None:
    """The objects that follow each other from the one at ``start`` and end by ``limit``
    (None: not even the first is whole and sound; ``read_object`` or the caller deals
    with it)."""
    buffer = np.frombuffer(data, np.uint8, count=limit)
    starts = _signatures(buffer, start)
    starts = starts[starts + _HEADER.itemsize <= limit]
    if not starts.shape[0] or starts[0] != start:
        return None
    headers = _rows(buffer, starts, _HEADER)
    ends = starts + headers["size"].astype(np.int64)
    least = np.zeros(starts.shape[0], np.int64)
    for version, size in HEADER_SIZES.items():
        least[headers["version"] == version] = size
    sound = (
        (least > 0)
        & (headers["header_size"] >= least)
        & (headers["size"] >= headers["header_size"])
        & (ends <= limit)
    )
    following = np.searchsorted(starts, ends)  # the first signature at or after each end
    nearest = starts[np.minimum(following, starts.shape[0] - 1)]
    linked = (following == np.arange(1, starts.shape[0] + 1)) & (nearest <= ends + _PADDING)
    linked[-1] = True  # the last one: its successor is not in ``data`` yet
    good = sound & linked
    count = starts.shape[0] if good.all() else int(np.argmin(good))
    if not count:
        return None
    return Chain(starts[:count], headers[:count], int(ends[count - 1]))


def message_columns(data: bytes, found: Chain, start_time: float) -> tuple[Array, FrameColumns]:
    """Which of the chained objects are CAN data frames read here (a bool per object),
    and those frames as columns."""
    headers = found.headers
    kinds = headers["type"]
    usable = np.isin(kinds, CAN_MESSAGES) & (headers["stamp"] < _EXACT)
    usable &= headers["size"] - headers["header_size"] >= CAN_MESSAGE_DATA.size
    rows = np.flatnonzero(usable)
    buffer = np.frombuffer(data, np.uint8)
    bodies = found.starts[rows] + headers["header_size"][rows].astype(np.int64)
    messages = _rows(buffer, bodies, _MESSAGE)
    stamps = headers["stamp"][rows].astype(np.float64)
    ten_micros = headers["flags"][rows] == TIME_TEN_MICROS
    times = np.where(ten_micros, stamps / 1e5, stamps / 1e9) + start_time
    plain = (messages["flags"] & REMOTE) == 0
    plain &= np.isfinite(times) & (np.abs(times) <= LATEST_TIME)  # else said one by one
    usable[rows[~plain]] = False
    messages, times = messages[plain], times[plain]
    length = np.minimum(messages["dlc"], 8).astype(np.uint8)
    payload = messages["data"] * (np.arange(8) < length[:, None])  # zero after the length
    ids = messages["id"].astype(np.int64)
    numbers = messages["channel"].astype(np.int64)
    channels = distinct(numbers)
    frames = FrameColumns(
        times,
        ids & 0x1FFFFFFF,
        (ids & EXTENDED_ID) != 0,
        length,
        payload.astype(np.uint8),
        np.searchsorted(channels, numbers).astype(np.int32),
        [str(number - 1) for number in channels],
        np.where(messages["flags"] & TRANSMITTED, 2, 1).astype(np.int8),
    )
    return usable, frames


def _signatures(buffer: Array, start: int) -> Array:
    """Where ``LOBJ`` starts in ``buffer`` at or after ``start``, ascending."""
    found = []
    size = buffer.shape[0]
    for shift in range(4):
        first = start + shift
        count = (size - first) // 4
        if count <= 0:
            continue
        words = np.ndarray((count,), "<u4", buffer.data, first, (4,))
        found.append(first + 4 * np.flatnonzero(words == _SIGNATURE))
    return np.sort(np.concatenate(found)) if found else np.zeros(0, np.int64)


def _rows(buffer: Array, at: Array, dtype: np.dtype[Any]) -> Array:
    """The records of ``dtype`` that start at ``at`` (byte offsets) in ``buffer``."""
    width = dtype.itemsize
    if buffer.shape[0] < width or not at.shape[0]:
        return np.zeros(0, dtype)
    windows = np.lib.stride_tricks.sliding_window_view(buffer, width)
    return np.ascontiguousarray(windows[at]).view(dtype).ravel()


assert BASE_HEADER.size + 16 == _HEADER.itemsize
