"""The one set of counters of a run: what every command reports about the same input.

Raw items (frames, chunks, bytes) and events (per topic, diagnostic kind, command),
the gimbal's feedback timing (rate, longest gap, gaps over a limit; each stream's a
``feedback_track.FeedbackTrack``) and the CRC error rate are defined here once.
``decode --summary``, ``convert``, ``record``, ``demo``, the monitor and ``info``
(from the record an MCAP sink writes at the end, or from a scan of the recorded
events) all read these figures.
"""

from __future__ import annotations

import json
from collections import Counter
from collections.abc import Iterable
from dataclasses import asdict, dataclass, field
from operator import attrgetter, itemgetter
from typing import Any

from analyzer.bus_figures import BusFigures
from analyzer.feedback_track import (
    FEEDBACK_TOPICS,
    FeedbackClock,
    FeedbackTrack,
    damaged_feedback,
    feedback_stream,
    optional_float,
    round_figure,
)
from analyzer.protocol.event_columns import EventColumns, EventGroup
from analyzer.protocol.frame_columns import FrameColumns
from analyzer.protocol.types import (
    BUS_ERROR,
    CRC_MISMATCH,
    TOPIC_ANALYSIS_RESPONSE,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    CanFrame,
    Event,
    StreamChunk,
)

# Bits of a CAN 2.0 frame without stuffing, besides the data: SOF, arbitration, control,
# CRC, ACK, EOF and the 3-bit intermission (131 bits for an extended 8-byte frame).
CAN_BITS_EXTENDED = 67
CAN_BITS_STANDARD = 47


_DATA = attrgetter("data")
_EXTENDED = attrgetter("extended")
_TOPIC = attrgetter("topic")
_TIME = attrgetter("time")
_WARNINGS = attrgetter("warnings")
_FIRST = itemgetter(0)


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
    # When each timed stream's feedback last came (it decides which streams are timed).
    clock: FeedbackClock = field(default_factory=FeedbackClock, repr=False, compare=False)

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
            if e.topic in FEEDBACK_TOPICS or damaged_feedback(e)
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
                if e.topic in FEEDBACK_TOPICS or damaged_feedback(e)
            ]
        )

    def _time_points(self, points: list[tuple[float, str, bool]]) -> None:
        """Feedback messages (time, stream, damaged) in the order they came; a run of
        whole messages of one stream is timed in one go."""
        feedback, clock = self.feedback, self.clock
        i, n = 0, len(points)
        while i < n:
            t, key, damaged = points[i]
            if damaged:
                silence = clock.damaged(key, t)
                if silence is not None:
                    feedback[key].damaged(silence)
                i += 1
                continue
            end = i + 1
            while end < n and points[end][1] == key and not points[end][2]:
                end += 1
            self.crc_checked += end - i
            arrivals = clock.messages(key, [p[0] for p in points[i:end]])
            if arrivals is None:  # one stream too many to time
                self.feedback_untracked += end - i
            else:
                track = feedback.get(key)
                if track is None:
                    track = feedback[key] = FeedbackTrack()
                track.add(arrivals)
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
            "crc_error_rate": round_figure(self.crc_error_rate),
            **({"feedback_untracked": self.feedback_untracked} if self.feedback_untracked else {}),
            **({"bus": self.bus.figures()} if self.bus else {}),
        }

    def items(self) -> dict[str, int]:
        """Raw item counters."""
        return {"frames": self.frames, "chunks": self.chunks, "bytes": self.bytes}

    def copy(self) -> Tally:
        """An independent snapshot."""
        kept = ("feedback", "bus", "clock")
        twin = Tally(**{k: v for k, v in asdict(self).items() if k not in kept})
        twin.bus = BusFigures.from_figures(self.bus.figures())
        twin.topics, twin.kinds = Counter(self.topics), Counter(self.kinds)
        twin.commands = Counter(self.commands)
        twin.feedback = {
            k: FeedbackTrack.from_figures(t.figures()) for k, t in self.feedback.items()
        }
        twin.clock = FeedbackClock(dict(self.clock.last_arrival))
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
            first_time=optional_float(data.get("first_time")),
            last_time=optional_float(data.get("last_time")),
            bus=BusFigures.from_figures(figures.get("bus") or {}),
        )
        # Timing goes on from each stream's last message.
        tally.clock = FeedbackClock(
            {k: t.last for k, t in tally.feedback.items() if t.last is not None}
        )
        return tally
