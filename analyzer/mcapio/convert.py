"""Offline conversion: decode a stream of raw items and write them with their events to MCAP."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from analyzer.pipeline import Batch
from analyzer.protocol.types import CanFrame, Event, StreamChunk

BATCH_ITEMS = 2000


@dataclass
class ConvertResult:
    items: int = 0
    frames: int = 0
    chunks: int = 0
    events: int = 0
    diagnostics: int = 0
    messages: int = 0
    seconds: float = 0.0


def convert_items(
    items: Iterable[Any],
    sink: Any,
    *,
    decoder: Any = None,
    progress: Callable[[ConvertResult], None] | None = None,
) -> ConvertResult:
    """Decode ``items`` (CanFrame / StreamChunk; ready-made Events pass through) into ``sink``.

    ``sink`` is a McapSink (or any Sink); it is not closed here. ``progress`` is called
    after every batch of about 2000 items.
    """
    if decoder is None:
        from analyzer.protocol.decoder import Decoder

        decoder = Decoder()
    result = ConvertResult()
    started = time.perf_counter()
    feed_can = decoder.feed_can
    feed_stream = decoder.feed_stream
    batch = Batch()
    raw = batch.items
    events = batch.events
    for item in items:
        if isinstance(item, CanFrame):
            raw.append(item)
            events.extend(feed_can(item))
        elif isinstance(item, StreamChunk):
            raw.append(item)
            events.extend(feed_stream(item))
        elif isinstance(item, Event):
            events.append(item)
        else:
            continue
        if len(raw) >= BATCH_ITEMS:
            _deliver(batch, sink, result)
            batch = Batch()
            raw = batch.items
            events = batch.events
            if progress is not None:
                result.seconds = time.perf_counter() - started
                progress(result)
    events.extend(decoder.close())
    _deliver(batch, sink, result)
    result.seconds = time.perf_counter() - started
    result.messages = int(getattr(sink, "messages_written", 0))
    if progress is not None:
        progress(result)
    return result


def _deliver(batch: Batch, sink: Any, result: ConvertResult) -> None:
    for item in batch.items:
        if isinstance(item, CanFrame):
            result.frames += 1
        else:
            result.chunks += 1
    result.items += len(batch.items)
    result.events += len(batch.events)
    result.diagnostics += sum(1 for e in batch.events if e.topic == "/diagnostics")
    sink.handle(batch)
