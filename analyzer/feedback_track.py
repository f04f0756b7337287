"""The gimbal's feedback in time: one stream's messages, its silences and what they lost.

A message should come about every 500 ms (``EXPECTED_FEEDBACK_HZ``); a silence of
``GAP_PERIODS`` periods or more lost messages (``lost_messages``). ``FeedbackTrack``
times one stream (its source and direction): rate, the longest gap, the silences that
lost messages, from the silences ``FeedbackClock`` yields: the one clock the counters
(``analyzer.tally``) and the analysis of the feedback's health both time feedback by.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from analyzer.protocol.lru import MAX_SOURCES
from analyzer.protocol.types import (
    CRC_MISMATCH,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_GIMBAL_RANGING,
    Event,
)

# A feedback message that came with a bad CRC ends the silence before it: it is counted
# as damaged, not also as lost. (An incomplete one lost a segment: it is reported when
# the next message comes, and its silence counts.)
DAMAGED_FEEDBACK = frozenset({CRC_MISMATCH})
# The gimbal answers with one feedback message (attitude or ranging) about every 500 ms.
EXPECTED_FEEDBACK_HZ = 2.0
FEEDBACK_TOLERANCE = 0.25  # a rate further off than this fraction is flagged
FEEDBACK_TOPICS = frozenset({TOPIC_GIMBAL_ATTITUDE, TOPIC_GIMBAL_RANGING})
FEEDBACK_PERIOD_S = 1 / EXPECTED_FEEDBACK_HZ
# A silence of this many feedback periods or more has lost at least one message.
GAP_PERIODS = 1.5
GAP_THRESHOLD_S = GAP_PERIODS * FEEDBACK_PERIOD_S  # 0.75 s at 2 Hz
# Streams whose feedback is timed one by one; a file naming millions of channels must not
# grow the tally (nor the stats record written into a recording) without limit.
MAX_FEEDBACK_SOURCES = MAX_SOURCES
_US = 1_000_000  # gaps are compared in whole microseconds, so equal gaps tie exactly
_MANY = 64  # messages timed at once with numpy (only columns bring that many)


def feedback_stream(event: Event) -> str:
    """The stream a feedback message belongs to: its source, and direction if any."""
    direction = event.fields.get("direction")
    return f"{event.source} {direction}" if direction else event.source


def damaged_feedback(event: Event) -> bool:
    """A diagnostic of a feedback message that came damaged (it ends a silence)."""
    return event.topic == TOPIC_DIAGNOSTICS and event.fields.get("kind") in DAMAGED_FEEDBACK


def lost_messages(silence_s: float, period_s: float = FEEDBACK_PERIOD_S) -> int:
    """Feedback messages lost in a silence between two messages, counted in periods.

    A silence of ``GAP_PERIODS`` (1.5) periods or more has lost at least one message; it
    lost round(silence / period) - 1 of them. A message a fraction of a millisecond early
    or late changes nothing: one lost message at 2 Hz leaves about 1.0 s (0.75..1.25 s
    counts one), two leave about 1.5 s. decode --summary, info, analyze, report and
    table all count with this one function.
    """
    if not silence_s >= GAP_PERIODS * period_s:  # also False for NaN
        return 0
    return max(1, math.floor(silence_s / period_s + 0.5) - 1)


@dataclass(frozen=True, slots=True)
class Silence:
    """The time between two arrivals of one stream's feedback (whole or damaged messages),
    in whole microseconds: a recording's nanosecond times and the file it was made from
    give the same silence."""

    start: float  # the arrival before
    end: float  # the arrival that ended it

    @property
    def gap_us(self) -> int:
        return round(self.end * _US) - round(self.start * _US)

    @property
    def lost(self) -> int:
        """Feedback messages lost in it (``lost_messages``)."""
        return lost_messages(self.gap_us / _US)


@dataclass(slots=True)
class Arrivals:
    """Whole messages of one stream at ``times``, after the arrival ``previous`` (None
    before the stream's first message); iterating gives the silences they end."""

    previous: float | None
    times: list[float]

    def __iter__(self) -> Iterator[Silence]:
        previous = self.previous
        for t in self.times:
            if previous is not None:
                yield Silence(previous, t)
            previous = t


@dataclass(slots=True)
class FeedbackClock:
    """When each stream's feedback last came, and the silences new messages end: the rules
    the counters (``analyzer.tally``) and the feedback's health (``analysis.health``) both
    time feedback by, written once.

    - A whole message ends the silence before it (a stream's first message ends none).
    - A message with a bad CRC came whole but damaged: it ends the silence before it too,
      so that silence is not also counted as lost, but only after a message of its stream
      and after the last arrival (``DAMAGED_FEEDBACK``; an incomplete one lost a segment,
      and its silence counts).
    - Only the first ``MAX_FEEDBACK_SOURCES`` streams are timed: a file naming millions of
      channels must not grow the figures without limit; the rest are counted, not timed.

    Sans-IO: times in, silences out.
    """

    last_arrival: dict[str, float] = field(default_factory=dict)  # stream -> its last

    def messages(self, stream: str, times: list[float]) -> Arrivals | None:
        """Whole messages of ``stream`` at ``times`` (one or more, in order): the silences
        they end, or None when the stream is one too many to time."""
        last = self.last_arrival
        previous = last.get(stream)
        if previous is None and len(last) >= MAX_FEEDBACK_SOURCES:
            return None
        if times:
            last[stream] = times[-1]
        return Arrivals(previous, times)

    def damaged(self, stream: str, t: float) -> Silence | None:
        """A message of ``stream`` with a bad CRC at ``t``: the silence it ends (None when
        its stream has had no message, or ``t`` is not after the last arrival)."""
        previous = self.last_arrival.get(stream)
        if previous is None or t <= previous:
            return None
        self.last_arrival[stream] = t
        return Silence(previous, t)


@dataclass
class FeedbackTrack:
    """The figures of one stream's feedback (source and direction): messages, rate, the
    longest gap and the silences that lost messages, from the silences its
    ``FeedbackClock`` yields.

    The longest gap is the first of the longest silences between two messages; times are
    compared in whole microseconds, so a recording (nanosecond times) and the file it was
    made from name the same gap.
    """

    count: int = 0
    first: float | None = None
    last: float | None = None
    longest_gap: float = 0.0
    gap_start: float | None = None  # the message before the longest gap
    gap_end: float | None = None  # the message that ended it
    gaps_over_threshold: int = 0  # silences that lost messages (see lost_messages)
    lost_messages: int = 0  # feedback messages lost in them
    _longest_us: int = field(default=0, repr=False)

    def add(self, arrivals: Arrivals) -> None:
        """Whole messages and the silences they end (those of many messages at once)."""
        times = arrivals.times
        if not times:
            return
        previous = arrivals.previous
        if previous is None:
            self.first = previous = times[0]
            times = times[1:]
            self.count += 1
        if len(times) > _MANY:
            self._silences(previous, times)
        else:
            previous_us = round(previous * _US)
            silence = self._silence
            for t in times:
                t_us = round(t * _US)
                silence(previous, t_us - previous_us, t)
                previous, previous_us = t, t_us
        self.count += len(times)
        self.last = arrivals.times[-1]

    def _silences(self, previous: float, times: list[float]) -> None:
        """``_silence`` between each two messages of ``previous`` and ``times``, at once:
        only the longest and those over the threshold need a closer look."""
        import numpy as np  # only for many messages at once: those of columns

        at = np.array([previous, *times])
        gaps = np.diff(np.rint(at * _US).astype(np.int64))
        longest = int(np.argmax(gaps))  # the first of the longest
        self._longest(float(at[longest]), int(gaps[longest]), float(at[longest + 1]))
        for gap_us in gaps[gaps / _US >= GAP_THRESHOLD_S].tolist():
            self._lost(gap_us)

    def damaged(self, silence: Silence) -> None:
        """The silence a message with a bad CRC ended: counted; the message itself is
        damaged, not lost."""
        self._silence(silence.start, silence.gap_us, silence.end)

    def _silence(self, last: float, gap_us: int, t: float) -> None:
        """The silence between messages at ``last`` and ``t`` (``gap_us`` microseconds)."""
        self._longest(last, gap_us, t)
        self._lost(gap_us)

    def _longest(self, last: float, gap_us: int, t: float) -> None:
        if gap_us > self._longest_us:
            self._longest_us = gap_us
            self.longest_gap, self.gap_start, self.gap_end = gap_us / _US, last, t

    def _lost(self, gap_us: int) -> None:
        lost = lost_messages(gap_us / _US)
        if lost:
            self.gaps_over_threshold += 1
            self.lost_messages += lost

    @property
    def rate_hz(self) -> float | None:
        if self.count < 2 or self.first is None or self.last is None:
            return None
        span = self.last - self.first
        return (self.count - 1) / span if span > 0 else None

    def figures(self) -> dict[str, Any]:
        """JSON-ready figures (rounded to microseconds)."""
        gap = self.count > 1
        return {
            "messages": self.count,
            "first": self.first,
            "last": self.last,
            "rate_hz": round_figure(self.rate_hz),
            "expected_hz": EXPECTED_FEEDBACK_HZ,
            "longest_gap_s": round(self.longest_gap, 6) if gap else None,
            "longest_gap_start": self.gap_start if gap else None,
            "longest_gap_end": self.gap_end if gap else None,
            "gap_threshold_s": GAP_THRESHOLD_S,
            "gaps_over_threshold": self.gaps_over_threshold,
            "lost_messages": self.lost_messages,
        }

    @classmethod
    def from_figures(cls, data: dict[str, Any]) -> FeedbackTrack:
        gap = data.get("longest_gap_s")
        track = cls(
            count=int(data["messages"]),
            first=optional_float(data.get("first")),
            last=optional_float(data.get("last")),
            longest_gap=float(gap or 0.0),
            gap_start=optional_float(data.get("longest_gap_start")),
            gap_end=optional_float(data.get("longest_gap_end")),
            gaps_over_threshold=int(data.get("gaps_over_threshold", 0)),
            lost_messages=int(data.get("lost_messages", 0)),
        )
        track._longest_us = round(track.longest_gap * _US)
        return track


def round_figure(value: float | None) -> float | None:
    return None if value is None else round(value, 6)


def optional_float(value: Any) -> float | None:
    if value is None or value == "":
        return None
    return float(value)
