"""The one path of every command: raw items -> decoder -> stages -> counters -> sinks.

``decode``, ``convert``, ``record``, ``monitor`` and ``demo`` all run a :class:`Pipeline`:
file commands drive it with :func:`run_reader`, live ones through the capture engine
(``analyzer.capture``), which feeds it from a reader thread. The pipeline itself never
reads a file, a socket or a clock.

An extra analysis plugs in once for every command as a :class:`Stage`: it sees every
batch of events after the decoder and may add events of its own (findings), which the
counters and sinks then see like any other event.
"""

from __future__ import annotations

import contextlib
import gc
import threading
from collections.abc import Callable, Iterable, Iterator, Sequence
from itertools import islice
from typing import Any, Protocol, cast

from analyzer.capture_clock import CaptureClock
from analyzer.pipeline_contracts import (
    Batch,
    BatchedItems,
    ColumnStage,
    Item,
    PipelineDecoder,
    RawItem,
    Sink,
    SinkFailure,
    Stage,
    keeps_items,
    takes_columns,
)
from analyzer.progress import Progress
from analyzer.protocol.frame_columns import FrameColumns
from analyzer.protocol.types import CanFrame, Event, StreamChunk
from analyzer.tally import Tally

_RAW_KINDS = frozenset({CanFrame, StreamChunk})

__all__ = [
    "BATCH_ITEMS",
    "Batch",
    "BatchedItems",
    "ColumnStage",
    "Item",
    "ItemReader",
    "Pipeline",
    "PipelineDecoder",
    "RawItem",
    "Sink",
    "SinkFailure",
    "Stage",
    "default_decoder",
    "delivered_batches",
    "fewer_collections",
    "keeps_items",
    "run_items",
    "run_reader",
    "takes_columns",
]

BATCH_ITEMS = 2000  # file commands hand a batch to the sinks after this many items


def default_decoder(*, emit_other: bool = False) -> PipelineDecoder:
    from analyzer.protocol.decoder import ProtocolDecoder

    return ProtocolDecoder(emit_other=emit_other)


class Pipeline:
    """Decodes raw items, runs the stages, counts everything once and feeds the sinks.

    ``feed`` decodes items into the open batch, ``deliver`` hands it over (stages,
    then the counters in ``tally``, then every sink that has not failed), ``finish``
    flushes the decoder and the stages, delivers the last batch and closes every sink.
    A sink that raises is set aside (``failures``) and the others go on; the driver
    decides whether to stop. ``lock`` guards ``tally`` for readers in other threads.
    """

    def __init__(
        self,
        sinks: Sequence[Sink] = (),
        *,
        decoder: PipelineDecoder | None = None,
        stages: Sequence[Stage] = (),
    ) -> None:
        self.decoder: PipelineDecoder = decoder if decoder is not None else default_decoder()
        self.sinks: list[Sink] = list(sinks)
        self.stages: list[Stage] = list(stages)
        self.tally = Tally()
        self.lock = threading.Lock()
        self.failures: list[SinkFailure] = []
        self.batch = Batch()
        self.delivered = 0  # batches handed to the sinks
        self.finished = False
        # A file's items dated by its capture (set by ``run_items``): see capture_clock.
        self.clock = CaptureClock()

    # -- input -------------------------------------------------------------------------------

    def feed(self, items: Iterable[Item]) -> None:
        """Decode items into the open batch; ready-made events go in as they are.

        The raw items go to the batch as they are; frames read as columns go there as
        CanFrames when a sink keeps raw items, else they are counted as columns."""
        items = items if type(items) is list else list(items)
        batch = self.batch
        self.decoder.feed_batch(items, batch.events, batch.columns)
        if set(map(type, items)) <= _RAW_KINDS:  # the usual batch
            batch.items += cast(list[RawItem], items)
            return
        keep = self.keeps_items
        for item in items:
            if isinstance(item, (CanFrame, StreamChunk)):
                batch.items.append(item)
            elif isinstance(item, FrameColumns):
                if keep:
                    batch.items += item.frames()
                else:
                    batch.runs.append(item)

    @property
    def keeps_items(self) -> bool:
        """Whether a sink looks at raw items (else frames read as columns stay columns)."""
        return any(map(keeps_items, self.sinks))

    def add_events(self, events: Iterable[Event]) -> None:
        """Events from outside the decoder (link changes, notes) into the open batch."""
        self.batch.events.extend(events)

    def tick(self, now: float) -> None:
        """Live input: let the decoder report partial messages older than its limits."""
        self.batch.events.extend(self.decoder.tick(now))

    @property
    def pending_items(self) -> int:
        return len(self.batch.items)

    # -- output ------------------------------------------------------------------------------

    def deliver(self, wall_time: float = 0.0, *, closing: bool = False) -> Batch:
        """Hand the open batch (possibly empty) to stages, counters and sinks; open a new one.

        ``closing`` (``finish``): each stage closes once it has seen the batch, so that
        what the decoder said at the end of the input reaches it before it closes."""
        batch = self.batch
        self.batch = Batch()
        batch.wall_time = wall_time
        batch.counted, batch.sequence = self.tally, self.delivered
        self.delivered += 1
        # The stages see every event as an Event (a column stage makes those it reads);
        # the sinks that take columns get the columns still, the others Events.
        for stage in self.stages:
            if batch.columns and isinstance(stage, ColumnStage):
                extra = stage.process_segments(batch.segments())
            else:
                extra = stage.process(batch.merged())
            if extra:
                batch.add(extra)
            if closing:
                batch.add(stage.close())
        with self.lock:
            self.tally.add_items(batch.items)
            self.tally.add_runs(batch.runs)
            if batch.columns:
                for segment in batch.segments():
                    if isinstance(segment, list):
                        self.tally.add_events(segment)
                    else:
                        self.tally.add_columns(segment)
            else:
                self.tally.add_events(batch.events)
        if batch.columns and not all(map(takes_columns, self.sinks)):
            batch.materialize()
        failed = {id(f.sink) for f in self.failures}
        for sink in self.sinks:
            if id(sink) in failed:
                continue
            try:
                sink.handle(batch)
            except Exception as exc:
                self.failures.append(SinkFailure(sink, exc))
        return batch

    def finish(self, wall_time: float = 0.0, extra: Iterable[Event] = ()) -> Batch:
        """End of input: flush the decoder, deliver the last batch (the stages see what the
        decoder flushed, then close), close every sink.

        Safe to call twice (the second call does nothing). ``extra`` events (a note on
        why the input ended) go into the last batch.
        """
        if self.finished:
            return Batch()
        self.finished = True
        events = self.batch.events
        try:
            events.extend(self.decoder.close())
        finally:
            events.extend(extra)
            try:
                batch = self.deliver(wall_time, closing=True)
            finally:
                failed = {id(f.sink) for f in self.failures}
                for sink in self.sinks:
                    try:
                        sink.close()
                    except Exception as exc:
                        if id(sink) not in failed:
                            self.failures.append(SinkFailure(sink, exc, closing=True))
        return batch

    @property
    def failed(self) -> bool:
        return bool(self.failures)

    def snapshot(self) -> Tally:
        """A copy of the counters, safe to read while another thread feeds the pipeline."""
        with self.lock:
            return self.tally.copy()


def run_items(
    items: Iterable[Any],
    pipeline: Pipeline,
    *,
    batch_items: int = BATCH_ITEMS,
    after_batch: Callable[[Batch], None] | None = None,
    progress: Progress | None = None,
) -> None:
    """Drive ``pipeline`` with everything ``items`` yields (a file reader), then finish it.

    ``delivered_batches`` does the work (see there: batches, an early stop
    when a sink fails, exceptions of the reader); ``after_batch`` runs after each batch
    but the last, the one ``finish`` delivers. ``progress``
    (``analyzer.progress.Progress.maybe``) is drawn after each batch and cleared at the
    end, whatever happens.
    """
    tally = pipeline.tally
    try:
        with fewer_collections():
            for batch in delivered_batches(items, pipeline, batch_items=batch_items):
                if pipeline.failed or pipeline.finished:
                    continue
                if after_batch is not None:
                    after_batch(batch)
                if progress is not None:
                    progress.update(tally.frames + tally.chunks)
    finally:
        if progress is not None:
            progress.clear()


class ItemReader(Protocol):
    """An input that ``run_reader`` reads (``analyzer.inputs.base.InputReader``): items,
    and a ``close`` that frees the file."""

    def __iter__(self) -> Iterator[Any]: ...

    def close(self) -> None: ...


def run_reader(
    reader: ItemReader,
    pipeline: Pipeline,
    *,
    batch_items: int = BATCH_ITEMS,
    progress: Progress | None = None,
    interruptible: bool = False,
) -> bool:
    """The run of every file command: ``reader`` through ``pipeline`` (``run_items``),
    the reader closed at the end whatever happens, then the error of a sink that failed
    raised. ``interruptible`` (live input, such as standard input): Ctrl-C ends the input
    as its end would (the pipeline finishes) and True is returned; else it propagates."""
    interrupted = False
    try:
        try:
            run_items(reader, pipeline, batch_items=batch_items, progress=progress)
        except KeyboardInterrupt:
            if not interruptible:
                raise
            interrupted = True
            pipeline.finish()
    finally:
        reader.close()
    for failure in pipeline.failures:
        raise failure.error
    return interrupted


def delivered_batches(
    items: Iterable[Any], pipeline: Pipeline, *, batch_items: int = BATCH_ITEMS
) -> Iterator[Batch]:
    """Feed ``pipeline`` everything ``items`` yields, yielding each batch once delivered;
    the last is the one ``finish`` delivers (the pipeline is then finished).

    A batch of at most ``batch_items`` items goes to the sinks at a time (a reader that
    reads in blocks hands on a block's items at once; 1 for live input such as standard
    input, so each line shows at once). The items are dated by the capture's own time
    (``analyzer.capture_clock``) on the way. Stops early (then finishes) when a sink fails. An
    exception of the reader (Ctrl-C, unreadable input) propagates without ``finish``:
    the caller decides whether what was read counts (``decode`` of live input finishes,
    ``convert`` throws its output away). ``run_items`` (the commands, through
    ``run_reader``) and the Python API's ``read`` and ``analyze`` are this one loop.
    """
    if isinstance(items, BatchedItems):
        chunks: Iterator[list[Any]] = items.batches(batch_items)
    else:
        chunks = _chunks(iter(items), batch_items)
    # Damage before the first frame, and frames dated far before the capture, take the
    # capture's time (never 1970).
    for chunk in pipeline.clock.batches(chunks):
        pipeline.feed(chunk)
        yield pipeline.deliver()
        if pipeline.failed:
            break
    yield pipeline.finish()


@contextlib.contextmanager
def fewer_collections(young: int = 50_000) -> Iterator[None]:
    """Run the cyclic garbage collector's youngest generation less often for a while.

    Decoding a file makes millions of short-lived objects (frames, events, their dicts)
    that reference counting frees and that form no cycles; with the default threshold
    (700 allocations) the collector would look at them again and again.
    """
    threshold = gc.get_threshold()
    gc.set_threshold(max(young, threshold[0]), *threshold[1:])
    try:
        yield
    finally:
        gc.set_threshold(*threshold)


def _chunks(iterator: Iterator[Any], size: int) -> Iterator[list[Any]]:
    while chunk := list(islice(iterator, size)):
        yield chunk
