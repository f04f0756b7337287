"""A file's items kept within its capture's time: damage before the first frame, and frames
whose time lies far before the capture, are dated by the capture's own frames.

A reader reports a line it cannot read as a diagnostic timed by the last frame it read,
and before any frame there is none: such a diagnostic would carry the time 0 (1970) and a
recording of the file would span fifty years. A timestamp damaged into a number that
still parses (a flipped digit) would do the same. :class:`CaptureClock` sits between the
reader and the decoder: diagnostics that come before the first frame wait for it and take
its time; a frame more than ``MAX_BACK_S`` before the capture (its first frames, or the
latest time read) becomes a ``bad_frame`` diagnostic that keeps its bytes, timed by the
capture. Frames in time order pass through untouched, a batch at a time.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import replace
from operator import attrgetter
from typing import Any

from analyzer.protocol.frame_columns import FrameColumns
from analyzer.protocol.types import (
    BAD_FRAME,
    TOPIC_DIAGNOSTICS,
    CanFrame,
    Event,
    StreamChunk,
    diagnostic,
)
from analyzer.timefmt import UTC

# A frame this far before the capture's time is no clock going back but a damaged one (a
# pcap record header this far from the last good time is garbage too).
MAX_BACK_S = 7 * 86400.0
_TIME = attrgetter("time")


def _time(item: Any) -> float:
    if type(item) is FrameColumns:
        return float(item.time.min())
    return float(item.time)


def _latest(item: Any) -> float:
    if type(item) is FrameColumns:
        return float(item.time.max())
    return float(item.time)


def _timed(item: Any) -> bool:
    """Frames, stream chunks, columns of frames and decoded events give the capture its
    time; readers' diagnostics follow it."""
    return not (type(item) is Event and item.topic == TOPIC_DIAGNOSTICS)


class CaptureClock:
    """Dates a reader's batches by the capture's own time (see the module docstring)."""

    def __init__(self, max_back_s: float = MAX_BACK_S) -> None:
        self.max_back_s = max_back_s
        self.first: float | None = None  # the capture's first good time
        self.latest: float | None = None
        self.redated = 0  # diagnostics that waited for the first frame
        self.quarantined = 0  # frames too far before the capture, kept as diagnostics
        self._held: list[Event] = []

    def bounded(self, t: float | None) -> float | None:
        """A time the reader gives for the capture (its first frame, skipped ones too),
        or the capture's first good time when ``t`` lies too far before it."""
        first = self.first
        if t is None or first is None or t >= first - self.max_back_s:
            return t
        return first

    def batches(self, chunks: Iterable[list[Any]]) -> Iterator[list[Any]]:
        """``chunks`` with their items dated; a chunk of nothing but early diagnostics is
        held and handed on with the first chunk that has a frame (or at the end)."""
        for chunk in chunks:
            out = self.date(chunk)
            if out:
                yield out
        if self._held:  # no frame at all: the diagnostics keep the times they had
            held, self._held = self._held, []
            yield held

    def date(self, chunk: list[Any]) -> list[Any]:
        """One chunk, dated; [] while only diagnostics have come."""
        if self.first is None:
            return self._start(chunk)
        if not chunk:
            return chunk
        kinds = set(map(type, chunk))
        if FrameColumns in kinds:
            earliest = min(_time(item) for item in chunk)
            latest = max(_latest(item) for item in chunk)
        else:
            times = list(map(_TIME, chunk))
            earliest, latest = min(times), max(times)
        assert self.latest is not None
        if earliest >= self.first and earliest >= self.latest - self.max_back_s:
            self.latest = max(self.latest, latest)
            return chunk
        return self._sorted_out(chunk)

    # -- the first frames -------------------------------------------------------------------

    def _start(self, chunk: list[Any]) -> list[Any]:
        times: list[float] = []
        for item in chunk:
            if type(item) is FrameColumns:
                times += item.time.tolist()
            elif _timed(item):
                times.append(float(item.time))
        if not times:
            self._held.extend(chunk)
            return []
        # The capture's time is where most of its first frames are: one damaged first
        # frame does not set it.
        reference = sorted(times)[(len(times) - 1) // 2]  # the lower median
        good = [t for t in times if t >= reference - self.max_back_s]
        self.first = self.latest = min(good)
        held, self._held = self._held, []
        return self._sorted_out(held + chunk)

    # -- the slow way: item by item ---------------------------------------------------------

    def _sorted_out(self, chunk: list[Any]) -> list[Any]:
        out: list[Any] = []
        for item in chunk:
            if type(item) is FrameColumns and self._too_early(_time(item)):
                out += [self._checked(frame) for frame in item.frames()]
                continue
            out.append(self._checked(item))
        return out

    def _checked(self, item: Any) -> Any:
        first = self.first
        assert first is not None
        if not _timed(item):
            if item.time < first:
                self.redated += 1
                return replace(item, time=first)
            return item
        if self._too_early(_time(item)):
            return self._quarantine(item)
        self.latest = max(self.latest or _latest(item), _latest(item))
        return item

    def _too_early(self, t: float) -> bool:
        first, latest = self.first, self.latest
        assert first is not None and latest is not None
        return t < first - self.max_back_s or t < latest - self.max_back_s

    def _quarantine(self, item: Any) -> Event:
        self.quarantined += 1
        when = self.latest
        assert when is not None
        t = _time(item)
        source, raw, what = _describe(item)
        # A diagnostic is data (recordings, JSON): its times are UTC, whatever is displayed.
        detail = (
            f"{what} timed {UTC.format_clock(t)}, more than {self.max_back_s / 86400:g} days "
            f"before the capture ({UTC.format_clock(when)}): a damaged timestamp; its bytes "
            "are kept here"
        )
        return diagnostic(when, source, BAD_FRAME, detail, raw, stated_time=t)


def _describe(item: Any) -> tuple[str, bytes, str]:
    """(source, bytes, words) of a frame, chunk or event for its diagnostic."""
    if isinstance(item, CanFrame):
        return item.channel or "can", item.data, f"CAN frame 0x{item.can_id:X}"
    if isinstance(item, StreamChunk):
        return item.source, item.data, f"{len(item.data)} stream bytes"
    return str(getattr(item, "source", "")), b"", f"{getattr(item, 'topic', 'an')} event"
