"""The one set of counters of a run: what every command reports about the same input.

Raw items (frames, chunks, bytes) and events (per topic, diagnostic kind, command),
the gimbal's feedback timing (rate, longest gap, gaps over a limit) and the CRC
error rate are defined here once. ``decode --summary``, ``convert``, ``record``,
``demo``, the monitor and ``info`` (from the record an MCAP sink writes at the end,
or from a scan of the recorded events) all read these figures.
"""

from __future__ import annotations

import json
import math
from collections import Counter
from collections.abc import Iterable
from dataclasses import asdict, dataclass, field
from operator import attrgetter, itemgetter
from typing import Any

from analyzer.bus_figures import BusFigures
from analyzer.protocol.event_columns import EventColumns, EventGroup
from analyzer.protocol.frame_columns import FrameColumns
from analyzer.protocol.lru import MAX_SOURCES
from analyzer.protocol.types import (
    BUS_ERROR,
    CRC_MISMATCH,
    TOPIC_ANALYSIS_RESPONSE,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_GIMBAL_RANGING,
    CanFrame,
    Event,
    StreamChunk,
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
# Bits of a CAN 2.0 frame without stuffing, besides the data: SOF, arbitration, control,
# CRC, ACK, EOF and the 3-bit intermission (131 bits for an extended 8-byte frame).
CAN_BITS_EXTENDED = 67
CAN_BITS_STANDARD = 47

_US = 1_000_000  # gaps are compared in whole microseconds, so equal gaps tie exactly
_MANY = 64  # messages timed at once with numpy (only columns bring that many)


def silence_s(previous: float, t: float) -> float:
    """The time between two messages in whole microseconds (a recording's nanosecond times
    and the file it was made from give the same silence)."""
    return (round(t * _US) - round(previous * _US)) / _US


def feedback_stream(event: Event) -> str:
    """The stream a feedback message belongs to: its source, and direction if any."""
    direction = event.fields.get("direction")
    return f"{event.source} {direction}" if direction else event.source


def _damaged_feedback(event: Event) -> bool:
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


_DATA = attrgetter("data")
_EXTENDED = attrgetter("extended")
_TOPIC = attrgetter("topic")
_TIME = attrgetter("time")
_WARNINGS = attrgetter("warnings")
_FIRST = itemgetter(0)


@dataclass
class FeedbackTrack:
    """The feedback messages of one stream (source and direction), one time at a time.

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
    # The last message that came, whole or damaged: a silence ends with either.
    _arrival: float | None = field(default=None, repr=False)

    def add(self, t: float) -> None:
        self.add_times([t])

    def add_times(self, times: list[float]) -> None:
        """Messages at ``times``, one after the other (``add`` of each, in one loop)."""
        if not times:
            return
        previous = self._arrival if self._arrival is not None else self.last
        if previous is None:
            self.first = previous = times[0]
            times = times[1:]
            self.count += 1
        if len(times) > _MANY:
            self._silences(previous, times)
            previous = times[-1]
        else:
            previous_us = round(previous * _US)
            silence = self._silence
            for t in times:
                t_us = round(t * _US)
                silence(previous, t_us - previous_us, t)
                previous, previous_us = t, t_us
        self.count += len(times)
        self.last = self._arrival = previous

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

    def damaged(self, t: float) -> None:
        """A message with a bad CRC came at ``t``: the silence before it ends there, and
        what it ends is counted; the message itself is damaged, not lost."""
        arrival = self._arrival if self._arrival is not None else self.last
        if arrival is None or t <= arrival:
            return
        self._silence(arrival, round(t * _US) - round(arrival * _US), t)
        self._arrival = t

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
            "rate_hz": _round(self.rate_hz),
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
            first=_opt_float(data.get("first")),
            last=_opt_float(data.get("last")),
            longest_gap=float(gap or 0.0),
            gap_start=_opt_float(data.get("longest_gap_start")),
            gap_end=_opt_float(data.get("longest_gap_end")),
            gaps_over_threshold=int(data.get("gaps_over_threshold", 0)),
            lost_messages=int(data.get("lost_messages", 0)),
        )
        track._longest_us = round(track.longest_gap * _US)
        return track


@dataclass
class Tally:
    """Counters of raw items and events, folded one batch at a time."""

    frames: int = 0
    chunks: int = 0
    bytes: int = 0
    bits: int = 0  # CAN bits on the wire without stuffing (for the bus load)
    events: int = 0  # every event, diagnostics included
    diagnostics: int = 0
    with_warnings: int = 0
    topics: Counter[str] = field(default_factory=Counter)
    kinds: Counter[str] = field(default_factory=Counter)
    commands: Counter[str] = field(default_factory=Counter)
    feedback: dict[str, FeedbackTrack] = field(default_factory=dict)
    # Feedback of streams beyond the first MAX_FEEDBACK_SOURCES: counted, not timed.
    feedback_untracked: int = 0
    crc_checked: int = 0  # messages whose CRC was checked and matched
    crc_errors: int = 0
    first_time: float | None = None
    last_time: float | None = None
    bus: BusFigures = field(default_factory=BusFigures)  # what the error frames say

    # -- folding -----------------------------------------------------------------------------

    def add_items(self, items: Iterable[CanFrame | StreamChunk]) -> None:
        """Count raw CAN frames / stream chunks (and widen the time span)."""
        items = items if isinstance(items, list) else list(items)
        if not items:
            return
        sizes = list(map(len, map(_DATA, items)))
        size = sum(sizes)
        if set(map(type, items)) == {CanFrame}:  # the usual batch: counted in C loops
            frames, chunks = len(items), 0
            extended = sum(map(_EXTENDED, items))
            bits = CAN_BITS_STANDARD * frames + 8 * size
            bits += (CAN_BITS_EXTENDED - CAN_BITS_STANDARD) * extended
        else:
            frames = chunks = bits = 0
            for item, n in zip(items, sizes, strict=True):
                if type(item) is CanFrame:
                    frames += 1
                    bits += (CAN_BITS_EXTENDED if item.extended else CAN_BITS_STANDARD) + 8 * n
                else:
                    chunks += 1
        self.frames += frames
        self.chunks += chunks
        self.bytes += size
        self.bits += bits
        times = list(map(_TIME, items))
        self.widen(min(times), max(times))

    def add_runs(self, runs: Iterable[FrameColumns]) -> None:
        """Count frames read as columns as ``add_items`` counts the same frames."""
        for run in runs:
            frames = len(run)
            if not frames:
                continue
            size = int(run.length.sum())
            extended = int(run.extended.sum())
            self.frames += frames
            self.bytes += size
            self.bits += CAN_BITS_STANDARD * frames + 8 * size
            self.bits += (CAN_BITS_EXTENDED - CAN_BITS_STANDARD) * extended
            self.widen(float(run.time.min()), float(run.time.max()))

    def add_columns(self, block: EventColumns) -> None:
        """Count the events of a block decoded in vectors as ``add_events`` counts them:
        its groups have no warnings and are counted by topic and command at once; the
        feedback messages of its groups are timed in frame order with its single events."""
        singles = block.single_events()
        firsts = [(int(g.rows[0]), str(g.name)) for g in block.groups if g.topic == TOPIC_COMMAND]
        if firsts:  # new names in the order they first came, as one by one
            firsts += [
                (row, str(e.fields.get("name", "unknown")))
                for row, e in singles
                if e.topic == TOPIC_COMMAND
            ]
            for _, name in sorted(firsts, key=_FIRST):
                if name not in self.commands:
                    self.commands[name] = 0
        feedback: list[EventGroup] = []
        for group in block.groups:
            n = len(group)
            self.events += n
            self.topics[group.topic] += n
            if group.topic == TOPIC_COMMAND:
                self.commands[str(group.name)] += n
            elif group.topic in FEEDBACK_TOPICS:
                feedback.append(group)
            self.widen(float(group.times.min()), float(group.times.max()))
        events = [e for _, e in singles]
        if events:
            self._count(events)
        if not feedback:
            self._time_feedback(events)
            return
        timed = [
            (row, e.time, feedback_stream(e), e.topic == TOPIC_DIAGNOSTICS)
            for row, e in singles
            if e.topic in FEEDBACK_TOPICS or _damaged_feedback(e)
        ]
        streams = {s for g in feedback for s in (g.sources[0], g.sources[-1])}
        if not timed and len(streams) == 1 and all(len(set(g.sources)) == 1 for g in feedback):
            import numpy as np  # the groups' rows and times are arrays already

            rows = np.concatenate([g.rows for g in feedback])
            times = np.concatenate([g.times for g in feedback])[np.argsort(rows, kind="stable")]
            key = streams.pop()
            self._time_points([(t, key, False) for t in times.tolist()])
            return
        for group in feedback:
            rows, times = group.rows.tolist(), group.times.tolist()
            timed += zip(rows, times, group.sources, [False] * len(rows), strict=True)
        timed.sort(key=_FIRST)
        self._time_points([(t, key, damaged) for _, t, key, damaged in timed])

    def add_events(self, events: Iterable[Event]) -> None:
        """Count events: per topic, diagnostic kind and command; feedback timing; CRCs.

        Findings of the response analysis are judgements, not input: not counted, so
        every command reports the same figures for the same input, stage or no stage.
        """
        events = events if isinstance(events, list) else list(events)
        if any(e.topic == TOPIC_ANALYSIS_RESPONSE for e in events):
            events = [e for e in events if e.topic != TOPIC_ANALYSIS_RESPONSE]
        if events:
            self._count(events)
            self._time_feedback(events)

    def _count(self, events: list[Event]) -> None:
        """Every count of ``add_events`` but the feedback's timing."""
        topics = list(map(_TOPIC, events))
        present = set(topics)
        # A batch holds few topics: each is counted in one C pass. The figures below pick
        # their events with a comprehension each, which beats chains of C iterators here.
        self.events += len(events)
        counts = self.topics
        for topic in present:
            counts[topic] += topics.count(topic)
        times = list(map(_TIME, events))
        self.widen(min(times), max(times))
        self.with_warnings += len(list(filter(None, map(_WARNINGS, events))))
        if TOPIC_COMMAND in present:
            names = [e.fields.get("name", "unknown") for e in events if e.topic == TOPIC_COMMAND]
            commands = self.commands
            for name in dict.fromkeys(names):  # in the order they came: ties stay put
                commands[str(name)] += names.count(name)
        if TOPIC_DIAGNOSTICS in present:
            kinds = [
                str(e.fields.get("kind", "unknown")) for e in events if e.topic == TOPIC_DIAGNOSTICS
            ]
            self.diagnostics += len(kinds)
            self.kinds.update(kinds)
            self.crc_errors += kinds.count(CRC_MISMATCH)
            if BUS_ERROR in kinds:
                self.bus.add_events(events)
        streamed = [e for e in events if "transport" in e.fields]  # read from a stream
        if streamed:
            self.crc_checked += sum(
                1
                for e in streamed
                if e.topic != TOPIC_DIAGNOSTICS
                and e.topic not in FEEDBACK_TOPICS
                and e.fields["transport"] == "stream"
                and e.fields.get("crc_set", True)
            )

    def _time_feedback(self, events: list[Event]) -> None:
        """The feedback messages of ``events`` timed, and damaged ones, in order: a
        damaged message ends the silence before it."""
        self._time_points(
            [
                (e.time, feedback_stream(e), e.topic == TOPIC_DIAGNOSTICS)
                for e in events
                if e.topic in FEEDBACK_TOPICS or _damaged_feedback(e)
            ]
        )

    def _time_points(self, points: list[tuple[float, str, bool]]) -> None:
        """Feedback messages (time, stream, damaged) in the order they came; a run of
        whole messages of one stream is timed in one go."""
        feedback = self.feedback
        i, n = 0, len(points)
        while i < n:
            t, key, damaged = points[i]
            if damaged:
                track = feedback.get(key)
                if track is not None:
                    track.damaged(t)
                i += 1
                continue
            end = i + 1
            while end < n and points[end][1] == key and not points[end][2]:
                end += 1
            self.crc_checked += end - i
            track = feedback.get(key)
            if track is None:
                if len(feedback) >= MAX_FEEDBACK_SOURCES:
                    self.feedback_untracked += end - i
                    i = end
                    continue
                track = feedback[key] = FeedbackTrack()
            track.add_times([p[0] for p in points[i:end]])
            i = end

    def widen(self, first: float | None, last: float | None) -> None:
        """Take a time span the input saw (frames the reader skipped, for instance) into account."""
        if first is not None and (self.first_time is None or first < self.first_time):
            self.first_time = first
        if last is not None and (self.last_time is None or last > self.last_time):
            self.last_time = last

    # -- figures -----------------------------------------------------------------------------

    @property
    def span(self) -> float:
        if self.first_time is None or self.last_time is None:
            return 0.0
        return self.last_time - self.first_time

    @property
    def crc_error_rate(self) -> float | None:
        total = self.crc_checked + self.crc_errors
        return self.crc_errors / total if total else None

    def figures(self) -> dict[str, Any]:
        """The figures every command reports, JSON-ready, under the same keys everywhere."""
        return {
            "events": self.events,
            "diagnostics": self.diagnostics,
            "events_with_warnings": self.with_warnings,
            "topics": dict(sorted(self.topics.items())),
            "diagnostics_by_kind": dict(sorted(self.kinds.items())),
            "commands": dict(sorted(self.commands.items())),
            "feedback": {k: t.figures() for k, t in sorted(self.feedback.items())},
            "crc_checked": self.crc_checked,
            "crc_errors": self.crc_errors,
            "crc_error_rate": _round(self.crc_error_rate),
            **({"feedback_untracked": self.feedback_untracked} if self.feedback_untracked else {}),
            **({"bus": self.bus.figures()} if self.bus else {}),
        }

    def items(self) -> dict[str, int]:
        """Raw item counters."""
        return {"frames": self.frames, "chunks": self.chunks, "bytes": self.bytes}

    def copy(self) -> Tally:
        """An independent snapshot."""
        twin = Tally(**{k: v for k, v in asdict(self).items() if k not in ("feedback", "bus")})
        twin.bus = BusFigures.from_figures(self.bus.figures())
        twin.topics, twin.kinds = Counter(self.topics), Counter(self.kinds)
        twin.commands = Counter(self.commands)
        twin.feedback = {
            k: FeedbackTrack.from_figures(t.figures()) for k, t in self.feedback.items()
        }
        return twin

    # -- as an MCAP metadata record ----------------------------------------------------------

    def to_metadata(self) -> dict[str, str]:
        """String values only, as MCAP metadata wants them."""
        return {
            "format": "tally/1",
            "figures": json.dumps(self.figures(), sort_keys=True),
            "items": json.dumps(self.items()),
            "first_time": "" if self.first_time is None else repr(self.first_time),
            "last_time": "" if self.last_time is None else repr(self.last_time),
        }

    @classmethod
    def from_metadata(cls, data: dict[str, str]) -> Tally:
        """Inverse of to_metadata; ValueError / KeyError / TypeError on a malformed record."""
        if data.get("format") != "tally/1":
            raise ValueError("not a tally record")
        figures = json.loads(data["figures"])
        items = json.loads(data["items"])
        tally = cls(
            frames=int(items["frames"]),
            chunks=int(items["chunks"]),
            bytes=int(items["bytes"]),
            events=int(figures["events"]),
            diagnostics=int(figures["diagnostics"]),
            with_warnings=int(figures["events_with_warnings"]),
            topics=Counter({str(k): int(v) for k, v in figures["topics"].items()}),
            kinds=Counter({str(k): int(v) for k, v in figures["diagnostics_by_kind"].items()}),
            commands=Counter({str(k): int(v) for k, v in figures["commands"].items()}),
            feedback={
                str(k): FeedbackTrack.from_figures(v) for k, v in figures["feedback"].items()
            },
            feedback_untracked=int(figures.get("feedback_untracked", 0)),
            crc_checked=int(figures["crc_checked"]),
            crc_errors=int(figures["crc_errors"]),
            first_time=_opt_float(data.get("first_time")),
            last_time=_opt_float(data.get("last_time")),
            bus=BusFigures.from_figures(figures.get("bus") or {}),
        )
        return tally


def _round(value: float | None) -> float | None:
    return None if value is None else round(value, 6)


def _opt_float(value: Any) -> float | None:
    if value is None or value == "":
        return None
    return float(value)
