"""Capture times of video frames on the telemetry's clock, from RTCP or anchored arrival times."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Generic, TypeVar

T = TypeVar("T")

# While a stream opens, a camera often sends what it has buffered in one burst: arrival
# times then say nothing about capture. Frames are held this long (seconds of arrival)
# before the clock is anchored, unless an RTCP sender report gives the mapping first.
SETTLE_S = 2.0
# ... or until frames have come in the stream's own pace this long: the smallest delay
# (arrival - stream time) has not dropped by more than STEADY_TOLERANCE_S since.
STEADY_S = 0.3
STEADY_TOLERANCE_S = 0.002
# An RTCP time is believed when the frame arrived this soon after it (seconds): a camera
# whose clock is not synchronised, or a sender report older than a restart of the
# stream, gives times off by more, and the arrival anchor is used instead.
RTCP_PLAUSIBLE = (-0.5, 1.5)
TIME_SOURCE_RTCP = "rtcp"
TIME_SOURCE_ARRIVAL = "arrival"


@dataclass(slots=True)
class Stamp:
    """A frame's stream time (seconds, from its pts), arrival time and, when the camera
    sent RTCP sender reports, its capture time from them (Unix seconds)."""

    stream_s: float
    arrival: float
    wallclock: float | None = None


class FrameClock(Generic[T]):
    """Turns stream timestamps into capture times on the local (telemetry) clock.

    With RTCP sender reports, a frame's time is the sender's wallclock for its RTP
    timestamp (FFmpeg's producer reference time), when that agrees with the local clock
    (the frame arrived within ``RTCP_PLAUSIBLE`` of it). Without them, time is the stream time
    plus an offset: the smallest ``arrival - stream time`` seen, i.e. the frame that came
    with the least delay anchors the stream's own spacing to the local clock. Frames are
    held back (``add`` returns nothing) until the anchor is known: once frames have come
    at the stream's own pace for ``STEADY_S`` (the burst a camera sends when a stream
    opens is over), at most ``settle_s`` seconds; so the burst keeps its spacing.
    Times never go backwards.
    """

    def __init__(self, settle_s: float = SETTLE_S, not_before: float = float("-inf")) -> None:
        self.settle_s = settle_s
        self.offset: float | None = None
        self.source = ""
        self._held: list[tuple[Stamp, T]] = []
        self._smallest = float("inf")  # smallest arrival - stream time while held
        self._steady_since = 0.0  # arrival time since when it has not dropped
        self._last = not_before  # times stay after this (the clock this one replaces)

    def add(self, stamp: Stamp, item: T) -> list[tuple[float, T]]:
        """Frames whose time is known now, as (capture time, item), in order."""
        low, high = RTCP_PLAUSIBLE
        if stamp.wallclock is not None and low <= stamp.arrival - stamp.wallclock <= high:
            self.offset = stamp.wallclock - stamp.stream_s
            self.source = TIME_SOURCE_RTCP
        elif self.offset is None:
            self._held.append((stamp, item))
            delay = stamp.arrival - stamp.stream_s
            if delay < self._smallest - STEADY_TOLERANCE_S:
                self._steady_since = stamp.arrival
            self._smallest = min(self._smallest, delay)
            first = self._held[0][0].arrival
            steady = len(self._held) > 2 and stamp.arrival - self._steady_since >= STEADY_S
            if stamp.arrival - first < self.settle_s and not steady:
                return []
            self.offset = min(s.arrival - s.stream_s for s, _ in self._held)
            self.source = TIME_SOURCE_ARRIVAL
            return list(self._release())
        elif self.source == TIME_SOURCE_ARRIVAL:
            self.offset = min(self.offset, stamp.arrival - stamp.stream_s)
        self._held.append((stamp, item))
        return list(self._release())

    @property
    def last(self) -> float:
        """The newest time given out."""
        return self._last

    def flush(self) -> list[tuple[float, T]]:
        """The end of the stream: held frames get the best anchor there is."""
        if self._held and self.offset is None:
            self.offset = min(s.arrival - s.stream_s for s, _ in self._held)
            self.source = TIME_SOURCE_ARRIVAL
        return list(self._release())

    def _release(self) -> Iterator[tuple[float, T]]:
        held, self._held = self._held, []
        offset = self.offset or 0.0
        for stamp, item in held:
            time = max(stamp.stream_s + offset, self._last + 1e-6)
            self._last = time
            yield time, item
