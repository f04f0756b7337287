"""What every file reader offers: iteration over items, progress in bytes, counters, close."""

from __future__ import annotations

import contextlib
import itertools
import math
import os
from collections.abc import Iterable, Iterator
from typing import IO, Any

from analyzer.errors import UsageError
from analyzer.protocol.frame_columns import FrameColumns
from analyzer.protocol.types import CanFrame, Event, StreamChunk

# FrameColumns: classic data frames a reader read in a block as arrays.
InputItem = CanFrame | StreamChunk | Event | FrameColumns
# Time bases (``InputReader.time_base``): how a file's times were written.
ABSOLUTE = "absolute"
RELATIVE_TO_START = "relative to the start of the recording"
DELTA = "time since the previous frame (accumulated)"
# Frame times are seconds since 1970 or since a log's start: a number beyond 2**33 s
# (the year 2242) is no time but a damaged field, and later steps cannot date it.
LATEST_TIME = float(2**33)


def time_problem(seconds: float) -> str | None:
    """Why ``seconds`` cannot be a frame's time (None when it can)."""
    if math.isfinite(seconds) and abs(seconds) <= LATEST_TIME:
        return None
    return f"time {seconds:g} s is out of range"


class InputReader:
    """Base of the file readers.

    Iterating gives ``CanFrame`` / ``StreamChunk`` items in file order, and ``Event``
    diagnostics for lines or records that could not be read (decoding goes on after
    them). ``size_bytes`` is the file size (None when unknown, e.g. standard input) and
    ``position_bytes`` how far reading has got, for a progress bar. ``stats`` counts what
    was read so that nothing is dropped silently.
    """

    format_name = "unknown"

    def __init__(self, path: str) -> None:
        self.path = path
        self.source = "stdin" if path == "-" else os.path.basename(path) or path
        self.size_bytes: int | None = None
        self.position_bytes = 0
        self.first_time: float | None = None  # time of the first frame read (skipped ones too)
        self.last_time: float | None = None
        # How the file's times were written, when it is worth saying: ABSOLUTE,
        # RELATIVE_TO_START or DELTA; None when not known.
        self.time_base: str | None = None
        # Facts about the input for the user that are no protocol diagnostic, known once
        # it has been read (e.g. "no TCP traffic on port 2000; ports seen: ...").
        self.notes: list[str] = []
        self._closers: list[Any] = []

    def __iter__(self) -> Iterator[InputItem]:
        raise NotImplementedError

    def batches(self, size: int) -> Iterator[list[InputItem]]:
        """The items in file order, in lists of at most ``size`` (a reader that reads in
        blocks hands on a block's items at once, which saves a step per item)."""
        iterator = iter(self)
        while chunk := list(itertools.islice(iterator, size)):
            yield chunk

    @property
    def stats(self) -> dict[str, int]:
        return {}

    def close(self) -> None:
        while self._closers:
            closer = self._closers.pop()
            with contextlib.suppress(Exception):  # must not hide the real outcome
                closer.close()

    def __enter__(self) -> InputReader:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _open_binary(self) -> IO[bytes]:
        """Open ``path`` for reading bytes; UsageError with one line when that fails."""
        handle = open_binary(self.path)
        self._closers.append(handle)
        try:
            self.size_bytes = os.fstat(handle.fileno()).st_size
        except OSError:
            self.size_bytes = None
        return handle


def open_binary(path: str) -> IO[bytes]:
    """Open a file for reading bytes, turning OS errors into a one-line UsageError."""
    if os.path.isdir(path):
        raise UsageError(f"{path} is a directory, not a capture file")
    try:
        return open(path, "rb")
    except FileNotFoundError:
        raise UsageError(f"no such file: {path}") from None
    except PermissionError:
        raise UsageError(f"cannot read {path}: permission denied") from None
    except OSError as exc:
        raise UsageError(f"cannot read {path}: {exc.strerror or exc}") from None


def one_by_one(batches: Iterable[list[InputItem]]) -> Iterator[InputItem]:
    """The items of ``batches`` one by one, frames read as columns as CanFrames (what a
    reader that reads in blocks gives when iterated)."""
    for items in batches:
        for item in items:
            if type(item) is FrameColumns:
                yield from item.frames()
            else:
                yield item


def by_frames(items: list[InputItem], size: int) -> Iterator[list[InputItem]]:
    """``items`` in lists of at most ``size`` frames (FrameColumns count their frames), in
    order; a run of more frames than that is a list of its own."""
    chunk: list[InputItem] = []
    weight = 0
    for item in items:
        frames = len(item) if type(item) is FrameColumns else 1
        if chunk and weight + frames > size:
            yield chunk
            chunk, weight = [], 0
        chunk.append(item)
        weight += frames
    yield chunk
