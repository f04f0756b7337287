"""What the pipeline hands on and asks of others: the Batch, and the Protocols of its sinks,
stages and decoder."""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

from analyzer.protocol.event_columns import ColumnSlots, EventColumns
from analyzer.protocol.frame_columns import FrameColumns
from analyzer.protocol.types import CanFrame, Event, StreamChunk
from analyzer.tally import Tally

RawItem = CanFrame | StreamChunk
Item = CanFrame | StreamChunk | Event | FrameColumns  # what readers deliver


@dataclass(slots=True)
class Batch:
    """Everything one step produced, in arrival order.

    ``items`` are the raw frames / stream chunks as read (lossless), ``events`` the
    decoded events and diagnostics they gave (link-state diagnostics and events of the
    stages included). ``runs`` holds the frames a reader read as columns
    (``FrameColumns``) when no sink keeps raw items (``Pipeline.keeps_items``); else they
    are in ``items`` as CanFrames.
    """

    items: list[RawItem] = field(default_factory=list)
    events: list[Event] = field(default_factory=list)
    wall_time: float = 0.0
    # Frames read as columns that no sink keeps: counted, never in ``items``.
    runs: list[FrameColumns] = field(default_factory=list)
    # The events of blocks decoded in vectors, not yet made into Events, each with its
    # place in ``events`` (``materialize`` puts them there; see ``segments``).
    columns: ColumnSlots = field(default_factory=list)
    # The pipeline's counters once this batch is counted, and how many batches it
    # delivered before this one: a sink that got every batch from the first may take the
    # counters as its own instead of counting each batch a second time.
    counted: Tally | None = None
    sequence: int = 0
    # Every event as an Event, in order, made once for the stages while the columns stay
    # for the sinks that take them (see ``merged``).
    _merged: list[Event] | None = field(default=None, repr=False)

    def segments(self) -> Iterator[list[Event] | EventColumns]:
        """The events in order: lists of Events and blocks of column events between them."""
        start = 0
        for place, block in self.columns:
            if place > start:
                yield self.events[start:place]
            yield block
            start = place
        if start < len(self.events):
            yield self.events[start:]

    def merged(self) -> list[Event]:
        """Every event in order as an Event (the column events made into Events once),
        the columns kept for the sinks that take them."""
        if not self.columns:
            return self.events
        if self._merged is None:
            events: list[Event] = []
            for segment in self.segments():
                events += segment if isinstance(segment, list) else segment.events()
            self._merged = events
        return self._merged

    def add(self, events: list[Event]) -> None:
        """Events made after decoding (a stage's findings): after every other event."""
        self.events.extend(events)
        if self._merged is not None:
            self._merged.extend(events)

    def materialize(self) -> list[Event]:
        """Make every column event an Event, in its place in ``events``; returns them."""
        if self.columns:
            self.events[:] = self.merged()
            self.columns.clear()
            self._merged = None
        return self.events


class Sink(Protocol):
    """Anything that consumes batches: MCAP writer, text printer, TUI bridge.

    A sink that never looks at ``Batch.items`` says so (``SaysItems``); then frames a
    reader read as columns are never built one by one. A sink that reads the events
    through ``Batch.segments`` says so (``SaysColumns``): the events of blocks decoded in
    vectors then reach it as columns; every other sink gets them as Events
    (``Batch.materialize``).
    """

    def handle(self, batch: Batch) -> None: ...

    def close(self) -> None: ...


@runtime_checkable
class SaysItems(Protocol):
    """A sink that says whether it looks at ``Batch.items`` (one without the attribute
    does)."""

    keeps_items: bool


@runtime_checkable
class SaysColumns(Protocol):
    """A sink that says whether it reads the events through ``Batch.segments`` (one
    without the attribute does not)."""

    takes_columns: bool


def keeps_items(sink: object) -> bool:
    """Whether ``sink`` looks at raw items."""
    return sink.keeps_items if isinstance(sink, SaysItems) else True


def takes_columns(sink: object) -> bool:
    """Whether ``sink`` takes the events of blocks decoded in vectors as columns."""
    return sink.takes_columns if isinstance(sink, SaysColumns) else False


class Stage(Protocol):
    """An analysis between decoder and sinks: events in, extra events out.

    ``process`` gets the events of each batch in order and returns the events it adds
    (often none); ``close`` returns what it still has to say at the end of the input.
    """

    def process(self, events: list[Event]) -> list[Event]: ...

    def close(self) -> list[Event]: ...


@runtime_checkable
class ColumnStage(Protocol):
    """A stage that takes a batch's events as the pipeline holds them (``Batch.segments``):
    lists of Events and blocks decoded in vectors, of which it makes Events itself only
    where it reads their fields (``analyzer.analysis.response.ResponseAnalyzer``)."""

    def process_segments(self, segments: Iterable[list[Event] | EventColumns]) -> list[Event]: ...


class PipelineDecoder(Protocol):
    """What the pipeline needs of a decoder (``analyzer.protocol.decoder.ProtocolDecoder``)."""

    def feed_can(self, frame: CanFrame) -> list[Event]: ...

    def feed_stream(self, chunk: StreamChunk) -> list[Event]: ...

    def feed_batch(
        self,
        items: Iterable[object],
        events: list[Event],
        columns: ColumnSlots | None = None,
    ) -> None: ...

    def tick(self, now: float) -> list[Event]: ...

    def close(self, now: float | None = None) -> list[Event]: ...


@runtime_checkable
class BatchedItems(Protocol):
    """A reader that hands on its items in lists (``analyzer.inputs.base.InputReader``)."""

    def batches(self, size: int) -> Iterator[list[Any]]: ...


@dataclass(slots=True)
class SinkFailure:
    """A sink that raised: it gets no more batches; ``error`` is what it raised."""

    sink: Sink
    error: BaseException
    closing: bool = False
