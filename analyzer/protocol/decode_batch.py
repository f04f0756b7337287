"""The decoder's batch path: in-place short ways for the usual frames, FrameRuns by column."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any, Protocol

from analyzer.protocol.command_decoders import COMMAND_DECODERS
from analyzer.protocol.event_columns import ColumnSlots, EventColumns
from analyzer.protocol.frame_columns import FrameColumns
from analyzer.protocol.ids import CONTROL_ID, FEEDBACK_ID
from analyzer.protocol.reassembly import FeedbackReassembler, Message
from analyzer.protocol.types import TOPIC_COMMAND, CanFrame, Event, FrameRun, StreamChunk
from analyzer.protocol.uav import EIGHT_BYTE_DECODERS, STATUS_FRAMES

# The extra fields of a plain CAN frame: none. Shared and never written to.
NO_EXTRA: dict[str, Any] = {}
STATUS_TOPICS = {can_id: status.topic for can_id, status in STATUS_FRAMES.items()}


class BatchDecoder(Protocol):
    """The decoder state ``feed_batch`` works on (``Decoder`` takes it as a method)."""

    frames: int
    protocol_frames: int
    last_time: float
    keep_column_frames: bool
    _recent: FeedbackReassembler | None
    _recent_source: str | None
    _given_up: list[Event]

    def _reassembler(self, source: str) -> FeedbackReassembler: ...
    def _take_given_up(self) -> list[Event]: ...
    def _feedback(
        self,
        source: str,
        results: list[Message | Event],
        extra: dict[str, Any],
        warnings: list[str] | None = None,
    ) -> list[Event]: ...
    def _can_any(self, frame: CanFrame, source: str, extra: dict[str, Any]) -> list[Event]: ...
    def decode_columns(self, frames: FrameColumns) -> EventColumns: ...
    def feed_stream(self, chunk: StreamChunk) -> list[Event]: ...


def feed_batch(
    decoder: BatchDecoder,
    items: Iterable[object],
    raw: list[CanFrame | StreamChunk],
    events: list[Event],
    columns: ColumnSlots | None = None,
) -> None:
    """Decode a batch in order: frames and chunks go to ``raw``, what they give to
    ``events``; ready-made events (diagnostics of a reader) go to ``events`` as they are.

    A block of frames as columns (``FrameColumns``) is decoded in vectors
    (``vector_decode``); its events go to ``columns`` with their place in ``events``
    (made into Events at once when ``columns`` is None), its frames to ``raw`` only when
    the decoder's ``keep_column_frames`` says so.

    The usual frame of a protocol ID (extended, no flags; 8 bytes of a command whose
    decoder was made or of a status frame) is decoded right here; any other goes
    through ``_can_any``, with the same result.
    """
    items = items if type(items) is list else list(items)
    add_event = events.append
    command_decoders = COMMAND_DECODERS
    status_decoders = EIGHT_BYTE_DECODERS
    status_topics = STATUS_TOPICS
    protocol = 0
    mixed = False  # anything but CAN frames in the batch
    for item in items:
        if type(item) is CanFrame:
            frame: CanFrame = item
            if frame.extended and not (frame.is_error or frame.is_remote or frame.is_fd):
                can_id = frame.can_id
                if can_id == CONTROL_ID:
                    data = frame.data
                    if len(data) == 8:
                        decode = command_decoders.get(data[0] << 8 | data[1])
                        if decode is not None:
                            fields, warnings = decode(data)
                            add_event(
                                Event(
                                    TOPIC_COMMAND,
                                    frame.time,
                                    frame.channel or "can",
                                    fields,
                                    warnings,
                                )
                            )
                            protocol += 1
                            continue
                if can_id == FEEDBACK_ID:
                    source = frame.channel or "can"
                    reassembler = decoder._recent if source == decoder._recent_source else None
                    if reassembler is None:
                        decoder.last_time = frame.time  # an eviction happens as of now
                        reassembler = decoder._reassembler(source)
                        if decoder._given_up:
                            events.extend(decoder._take_given_up())
                    results = reassembler.feed(frame.data, frame.time)
                    if results:
                        events.extend(decoder._feedback(source, results, NO_EXTRA))
                    protocol += 1
                    continue
                decode = status_decoders.get(can_id)
                if decode is not None and len(frame.data) == 8:
                    data = frame.data
                    fields, status_warnings = decode(data)
                    fields["raw"] = data.hex(" ").upper()
                    add_event(
                        Event(
                            status_topics[can_id],
                            frame.time,
                            frame.channel or "can",
                            fields,
                            status_warnings,
                        )
                    )
                    protocol += 1
                    continue
            decoder.last_time = frame.time
            events.extend(decoder._can_any(frame, frame.channel or "can", NO_EXTRA))
        else:
            mixed = True
            if type(item) is FrameColumns:
                decoded = decoder.decode_columns(item)
                if columns is None:
                    events.extend(decoded.events())
                else:
                    columns.append((len(events), decoded))
            elif type(item) is FrameRun:
                feed_run(decoder, item, events)
            elif type(item) is StreamChunk:
                events.extend(decoder.feed_stream(item))
            elif isinstance(item, Event):
                add_event(item)
    if mixed:
        raw_items = [i for i in items if type(i) is CanFrame or type(i) is StreamChunk]
        frames = sum(1 for i in raw_items if type(i) is CanFrame)
        if decoder.keep_column_frames and any(type(i) is FrameColumns for i in items):
            raw_items = []
            for i in items:
                if type(i) is CanFrame or type(i) is StreamChunk:
                    raw_items.append(i)
                elif type(i) is FrameColumns:
                    raw_items.extend(i.frames())
    else:
        raw_items, frames = items, len(items)  # type: ignore[assignment]
    raw.extend(raw_items)
    decoder.frames += frames
    decoder.protocol_frames += protocol
    if raw:
        last = raw[-1]
        if type(last) is CanFrame:
            decoder.last_time = last.time
    if mixed:  # a run after the last raw item: its last frame is the latest
        for item in reversed(items):
            if type(item) is FrameRun and len(item):
                decoder.last_time = item.time[-1]
            if type(item) is FrameColumns and len(item):
                decoder.last_time = float(item.time[-1])
            if type(item) is not Event:
                break


def feed_run(decoder: BatchDecoder, run: FrameRun, events: list[Event]) -> None:
    """Decode a run of plain frames, column by column, as ``feed_batch`` decodes them
    one CanFrame at a time (a frame not decoded here goes through ``_can_any``)."""
    add_event = events.append
    command_decoders = COMMAND_DECODERS
    status_decoders = EIGHT_BYTE_DECODERS
    status_topics = STATUS_TOPICS
    protocol = 0
    for time, (channel, can_id, extended), data, direction in zip(
        run.time, run.place, run.data, run.direction, strict=True
    ):
        if extended:
            if can_id == CONTROL_ID and len(data) == 8:
                decode = command_decoders.get(data[0] << 8 | data[1])
                if decode is not None:
                    fields, warnings = decode(data)
                    add_event(Event(TOPIC_COMMAND, time, channel or "can", fields, warnings))
                    protocol += 1
                    continue
            if can_id == FEEDBACK_ID:
                source = channel or "can"
                reassembler = decoder._recent if source == decoder._recent_source else None
                if reassembler is None:
                    decoder.last_time = time  # an eviction happens as of now
                    reassembler = decoder._reassembler(source)
                    if decoder._given_up:
                        events.extend(decoder._take_given_up())
                results = reassembler.feed(data, time)
                if results:
                    events.extend(decoder._feedback(source, results, NO_EXTRA))
                protocol += 1
                continue
            decode = status_decoders.get(can_id)
            if decode is not None and len(data) == 8:
                fields, status_warnings = decode(data)
                fields["raw"] = data.hex(" ").upper()
                add_event(
                    Event(status_topics[can_id], time, channel or "can", fields, status_warnings)
                )
                protocol += 1
                continue
        decoder.last_time = time
        frame = CanFrame(time, can_id, data, extended, channel, False, False, False, direction)
        events.extend(decoder._can_any(frame, channel or "can", NO_EXTRA))
    decoder.frames += len(run)
    decoder.protocol_frames += protocol
