"""Raw items and decoded events of a batch as MCAP messages, in time order, with their views."""

from __future__ import annotations

import operator
from collections.abc import Sequence

import orjson

from analyzer.mcapio.channels import (
    FLOAT_AS_REPR_FROM,
    FRAME_OPEN,
    FRAME_PARTS,
    ORJSON_OPTIONS,
    ROLE_EVENT,
    ROLE_RAW,
    ROLE_VIEW,
    TOPIC_CAN_FRAMES,
    TOPIC_STREAM_BYTES,
    FramePartsKey,
    MessageTee,
    can_frame_json,
    frame_parts,
    json_bytes,
    json_default,
    stream_chunk_json,
)
from analyzer.mcapio.foxglove import VIEW_INPUT_TOPICS, FoxgloveViews
from analyzer.mcapio.log_time import MAX_LOG_SECONDS, time_ns
from analyzer.mcapio.write.channel_registry import ChannelRegistry
from analyzer.mcapio.write.chunked_writer import ChunkedWriter
from analyzer.pipeline import RawItem
from analyzer.protocol.types import CanFrame, Event, StreamChunk
from analyzer.tally import Tally

_time_of = operator.attrgetter("time")


class MessageWriter:
    """Writes items to the lossless raw channels and events to their topic's JSON channel
    (plus their Foxglove views), counting what it wrote and adding it to ``tally``; a
    ``tee`` (the live server) gets every message with the very bytes written."""

    def __init__(
        self,
        writer: ChunkedWriter,
        channels: ChannelRegistry,
        tally: Tally,
        views: FoxgloveViews | None,
        tee: MessageTee | None = None,
    ) -> None:
        self._writer = writer
        self._tee = tee
        self._registry = channels
        self._views = views
        self.tally = tally
        self._shared = False  # ``tally`` is the pipeline's, which counts every batch
        self.items_written = 0
        self.events_written = 0
        self.messages_written = 0
        self.last_time: float | None = None
        self.dirty = False  # written since the last flush

    def share_tally(self, tally: Tally) -> None:
        """Take ``tally`` as this writer's counters, before anything is written: counters
        that count every batch this writer gets (the pipeline's, from its first batch),
        so that no batch is counted twice. Only for a writer no other thread reads."""
        if self.messages_written == 0 and not self._shared:
            self.tally, self._shared = tally, True

    def write_batch(self, items: list[RawItem], events: list[Event]) -> None:
        """Items and events of one batch, merged in time order (an item before its events)."""
        if not events or (items and items[-1].time <= events[0].time):
            self._put([*items, *events])
        elif not items:
            self._put(events)
        else:
            self._put(sorted([*items, *events], key=_time_of))
        if not self._shared:
            self.tally.add_items(items)
            self.tally.add_events(events)

    def write_items(self, items: list[RawItem]) -> None:
        self._put(items)
        self._own_tally().add_items(items)

    def write_events(self, events: list[Event]) -> None:
        self._put(events)
        self._own_tally().add_events(events)

    def _own_tally(self) -> Tally:
        """The counters to add a message written outside the batches to: a shared tally
        is copied first (the pipeline never saw that message)."""
        if self._shared:
            self.tally, self._shared = self.tally.copy(), False
        return self.tally

    def _put(self, messages: Sequence[RawItem | Event]) -> None:
        """Each raw item to its lossless channel, each event to its topic's channel (and its
        views), in the order given: one loop, as this runs for every frame of a file
        (benchmarks/convert_speed.py). The messages go to the writer together at the end (or
        before a new channel's record)."""
        if not messages:
            return
        out: list[tuple[int, int, bytes, int, int]] = []
        add = out.append
        registry = self._registry
        sequence = registry.sequence
        channels = registry.ids
        views = self._views
        can_id = channels.get(TOPIC_CAN_FRAMES, 0)
        can_number = sequence[can_id] if can_id else 0  # kept here, stored at the end
        events = extra = 0
        try:
            for message in messages:
                kind = type(message)
                if kind is CanFrame:
                    if not can_id:
                        can_id = self._channel(TOPIC_CAN_FRAMES, ROLE_RAW, out)
                        can_number = sequence[can_id]
                    encoded, log_time = frame_message(message)  # type: ignore[arg-type]
                    can_number += 1
                    add((can_id, log_time, encoded, log_time, can_number))
                elif kind is Event:
                    event: Event = message  # type: ignore[assignment]
                    topic = event.topic
                    channel_id = channels.get(topic) or self._channel(topic, ROLE_EVENT, out)
                    t = event.time
                    log_time = round(t * 1e9) if 0 < t < MAX_LOG_SECONDS else time_ns(t)
                    number = sequence[channel_id] + 1
                    sequence[channel_id] = number
                    add((channel_id, log_time, event_message(event), log_time, number))
                    events += 1
                    if views is not None and topic in VIEW_INPUT_TOPICS:
                        extra += self._put_views(views, event, log_time, out)
                else:
                    self._put_chunk(message, out)  # type: ignore[arg-type]
        finally:
            if can_id:
                sequence[can_id] = can_number
        self._written(messages, out, events, extra)

    def _put_views(
        self,
        views: FoxgloveViews,
        event: Event,
        log_time: int,
        out: list[tuple[int, int, bytes, int, int]],
    ) -> int:
        """The Foxglove views of ``event`` to their channels; how many."""
        channels, sequence = self._registry.ids, self._registry.sequence
        added = 0
        for view_topic, view in views.views(event):
            view_id = channels.get(view_topic) or self._channel(view_topic, ROLE_VIEW, out)
            number = sequence[view_id] + 1
            sequence[view_id] = number
            out.append((view_id, log_time, json_bytes(view), log_time, number))
            added += 1
        return added

    def _put_chunk(self, chunk: StreamChunk, out: list[tuple[int, int, bytes, int, int]]) -> None:
        """A stream's bytes (TCP, UART) to their lossless channel."""
        channels, sequence = self._registry.ids, self._registry.sequence
        topic = TOPIC_STREAM_BYTES
        channel_id = channels.get(topic) or self._channel(topic, ROLE_RAW, out)
        encoded = stream_chunk_json(chunk)
        t = chunk.time
        log_time = round(t * 1e9) if 0 < t < MAX_LOG_SECONDS else time_ns(t)
        number = sequence[channel_id] + 1
        sequence[channel_id] = number
        out.append((channel_id, log_time, encoded, log_time, number))

    def _written(
        self,
        messages: Sequence[RawItem | Event],
        out: list[tuple[int, int, bytes, int, int]],
        events: int,
        extra: int,
    ) -> None:
        """The messages to the writer, and the counts of what was written."""
        items = len(messages) - events
        self._write(out)
        self.items_written += items
        self.events_written += events
        self.messages_written += items + events + extra
        self.dirty = True
        self.last_time = messages[-1].time

    def _channel(
        self, topic: str, role: str, pending: list[tuple[int, int, bytes, int, int]]
    ) -> int:
        """A new channel: the messages before it are written first, so that its record
        goes into the open chunk where the message that needs it comes."""
        self._write(pending)
        pending.clear()
        return self._registry.channel(topic, role)

    def _write(self, messages: list[tuple[int, int, bytes, int, int]]) -> None:
        if self._tee is None:
            self._writer.add_messages(messages)
            return
        for channel_id, log_time, data, publish_time, number in messages:
            self._writer.add_message(channel_id, log_time, data, publish_time, number)
            self._tee.add_message(channel_id, log_time, data)


def frame_message(frame: CanFrame) -> tuple[bytes, int]:
    """A frame's JSON message and its log time (ns): the usual frame's JSON is put
    together from cached parts (``can_frame_json`` for the rest)."""
    t = frame.time
    if type(t) is float and FLOAT_AS_REPR_FROM <= t < MAX_LOG_SECONDS and not frame.is_remote:
        data = frame.data
        key: FramePartsKey = (
            frame.can_id,
            frame.extended,
            len(data),
            frame.channel,
            frame.is_error,
            frame.is_fd,
            frame.direction,
        )
        middle, tail = FRAME_PARTS.get(key) or frame_parts(frame, key)
        encoded = b"".join(
            (FRAME_OPEN, orjson.dumps(t), middle, data.hex(" ").upper().encode(), tail)
        )
        return encoded, round(t * 1e9)
    log_time = round(t * 1e9) if 0 < t < MAX_LOG_SECONDS else time_ns(t)
    return can_frame_json(frame), log_time


def event_message(event: Event) -> bytes:
    """An event's JSON message (``json_bytes(event.to_dict())``, with orjson when it can)."""
    content = {
        "topic": event.topic,
        "time": event.time,
        "source": event.source,
        "warnings": event.warnings,
        **event.fields,
    }
    try:
        return orjson.dumps(content, default=json_default, option=ORJSON_OPTIONS)
    except (orjson.JSONEncodeError, TypeError):
        return json_bytes(content)
