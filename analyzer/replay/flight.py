"""A flight read for a replay: the frames to send, the gimbal's attitude, the span replayed."""

from __future__ import annotations

from dataclasses import dataclass, field

from analyzer.analysis.samples import Sample, sample_from
from analyzer.pipeline import Batch
from analyzer.protocol.types import TOPIC_GIMBAL_ATTITUDE, TOPIC_GIMBAL_RANGING
from analyzer.replay.frames import Outgoing, outgoing


class FlightError(ValueError):
    """A flight that cannot be replayed (no command, an empty span): says why in one line."""


class FlightReader:
    """A pipeline sink that keeps what a replay needs of a flight: the ground station's
    frames, the attitude feedback, how much feedback it skips, the flight's first and last
    time (of any event)."""

    keeps_items = False

    def __init__(self) -> None:
        self.frames: list[Outgoing] = []
        self.samples: list[Sample] = []
        self.feedback = 0  # gimbal feedback messages: never sent
        self.first: float | None = None
        self.last: float | None = None

    def handle(self, batch: Batch) -> None:
        for event in batch.events:
            t = event.time
            self.first = t if self.first is None else min(self.first, t)
            self.last = t if self.last is None else max(self.last, t)
            topic = event.topic
            if topic == TOPIC_GIMBAL_ATTITUDE:
                self.feedback += 1
                sample = sample_from(t, event.fields, event.warnings)
                if sample is not None:
                    self.samples.append(sample)
            elif topic == TOPIC_GIMBAL_RANGING:
                self.feedback += 1
            else:
                self.frames.extend(outgoing(event))

    def close(self) -> None:
        self.frames.sort(key=lambda f: f.time)  # a text's frames spread back over its time
        self.samples.sort(key=lambda s: s.time)


@dataclass(frozen=True)
class Span:
    """The part of a flight a replay sends: from ``start`` to ``end`` (Unix s, the flight's
    clock), its frames, and the attitude the gimbal had when it began (``attitude``: the
    last feedback before it, else the first in it; None without feedback)."""

    source: str
    flight_start: float  # the flight's first event: seconds into the flight count from it
    start: float
    end: float
    frames: list[Outgoing]
    attitude: Sample | None
    skipped_feedback: int = 0
    refused: list[Outgoing] = field(default_factory=list)

    @property
    def start_s(self) -> float:
        return self.start - self.flight_start

    @property
    def end_s(self) -> float:
        return self.end - self.flight_start

    @property
    def commands(self) -> int:
        return sum(1 for f in self.frames if f.is_command)

    @property
    def status(self) -> int:
        return sum(1 for f in self.frames if not f.is_command)

    def words(self) -> str:
        """'0.0 s to 36.0 s of the flight'."""
        return f"{self.start_s:.1f} s to {self.end_s:.1f} s of the flight"


def span_of(
    reader: FlightReader, source: str, start_s: float = 0.0, end_s: float | None = None
) -> Span:
    """The frames from ``start_s`` to ``end_s`` seconds into the flight (its first event is
    0; None: to its last). FlightError when the flight or the span holds no command."""
    if reader.first is None or reader.last is None:
        raise FlightError(f"{source} holds no event at all: nothing to replay")
    length = reader.last - reader.first
    commands = [f for f in reader.frames if f.is_command]
    if not commands:
        raise FlightError(
            f"{source} holds no ground-station command (only {_counted(reader)}): nothing to replay"
        )
    if start_s > length:
        raise FlightError(f"--start {start_s:g} s is after the flight's end ({length:.1f} s)")
    start = reader.first + start_s
    end = reader.last if end_s is None else min(reader.last, reader.first + end_s)
    inside = [f for f in reader.frames if start <= f.time <= end]
    if not any(f.is_command for f in inside):
        first, last = commands[0].time - reader.first, commands[-1].time - reader.first
        raise FlightError(
            f"no ground-station command from {start_s:.1f} s to {end - reader.first:.1f} s of "
            f"the flight (its commands are from {first:.1f} s to {last:.1f} s)"
        )
    before = [s for s in reader.samples if s.time <= start]
    after = [s for s in reader.samples if start < s.time <= end]
    attitude = before[-1] if before else (after[0] if after else None)
    return Span(
        source,
        reader.first,
        start,
        end,
        [f for f in inside if not f.refused],
        attitude,
        len(after),
        [f for f in inside if f.refused],
    )


def _counted(reader: FlightReader) -> str:
    parts = [f"{reader.feedback:,} feedback messages"] if reader.feedback else []
    status = len(reader.frames)
    if status:
        parts.append(f"{status:,} UAV status frames")
    return ", ".join(parts) or "nothing a ground station sends"
