"""Raw items and decoded events of a batch as MCAP messages, in time order, with their views."""

from __future__ import annotations

import itertools
import operator
from collections.abc import Iterable

from analyzer.mcapio.channel_registry import ChannelRegistry
from analyzer.mcapio.channels import (
    ROLE_EVENT,
    ROLE_RAW,
    ROLE_VIEW,
    TOPIC_CAN_FRAMES,
    TOPIC_STREAM_BYTES,
    MessageTee,
    can_frame_json,
    stream_chunk_json,
    time_ns,
)
from analyzer.mcapio.channels import encode_json as _ENCODE
from analyzer.mcapio.chunked_writer import ChunkedWriter
from analyzer.mcapio.foxglove import VIEW_INPUT_TOPICS, FoxgloveViews
from analyzer.pipeline import RawItem
from analyzer.protocol.types import CanFrame, Event
from analyzer.tally import Tally

_time_of = operator.attrgetter("time")


def _is_event(value: object) -> bool:
    return isinstance(value, Event)


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
        self.items_written = 0
        self.events_written = 0
        self.messages_written = 0
        self.last_time: float | None = None
        self.dirty = False  # written since the last flush

    def write_batch(self, items: list[RawItem], events: list[Event]) -> None:
        """Items and events of one batch, merged in time order (an item before its events)."""
        if not events or (items and items[-1].time <= events[0].time):
            self.write_items(items)
            self.write_events(events)
            return
        if not items:
            self.write_events(events)
            return
        merged: list[RawItem | Event] = sorted([*items, *events], key=_time_of)
        # Frames and their events alternate: written run by run, counted once per batch.
        for is_event, run in itertools.groupby(merged, key=_is_event):
            if is_event:
                self._put_events(run)  # type: ignore[arg-type]
            else:
                self._put_items(run)  # type: ignore[arg-type]
        self.tally.add_items(items)
        self.tally.add_events(events)
        self.dirty = True
        self.last_time = merged[-1].time

    def write_items(self, items: list[RawItem]) -> None:
        self._put_items(items)
        self.tally.add_items(items)
        if items:
            self.dirty = True
            self.last_time = items[-1].time

    def write_events(self, events: list[Event]) -> None:
        self._put_events(events)
        self.tally.add_events(events)
        if events:
            self.dirty = True
            self.last_time = events[-1].time

    def _put_items(self, items: Iterable[RawItem]) -> None:
        add = self._writer.add_message if self._tee is None else self._add_teed
        registry = self._registry
        sequence = registry.sequence
        can_id = registry.ids.get(TOPIC_CAN_FRAMES, 0)
        stream_id = registry.ids.get(TOPIC_STREAM_BYTES, 0)
        written = 0
        for item in items:
            if isinstance(item, CanFrame):
                channel_id = can_id or registry.channel(TOPIC_CAN_FRAMES, ROLE_RAW)
                can_id = channel_id
                data = can_frame_json(item)
            else:
                channel_id = stream_id or registry.channel(TOPIC_STREAM_BYTES, ROLE_RAW)
                stream_id = channel_id
                data = stream_chunk_json(item)
            log_time = time_ns(item.time)
            number = sequence[channel_id] + 1
            sequence[channel_id] = number
            add(channel_id, log_time, data, log_time, number)
            written += 1
        self.messages_written += written
        self.items_written += written

    def _put_events(self, events: Iterable[Event]) -> None:
        add = self._writer.add_message if self._tee is None else self._add_teed
        registry = self._registry
        sequence = registry.sequence
        channels = registry.ids
        views = self._views
        for event in events:
            topic = event.topic
            channel_id = channels.get(topic) or registry.channel(topic, ROLE_EVENT)
            log_time = time_ns(event.time)
            number = sequence[channel_id] + 1
            sequence[channel_id] = number
            add(channel_id, log_time, _ENCODE(event.to_dict()).encode(), log_time, number)
            self.messages_written += 1
            self.events_written += 1
            if views is not None and topic in VIEW_INPUT_TOPICS:
                for view_topic, message in views.views(event):
                    view_id = channels.get(view_topic) or registry.channel(view_topic, ROLE_VIEW)
                    number = sequence[view_id] + 1
                    sequence[view_id] = number
                    add(view_id, log_time, _ENCODE(message).encode(), log_time, number)
                    self.messages_written += 1

    def _add_teed(
        self, channel_id: int, log_time: int, data: bytes, publish_time: int, sequence: int
    ) -> None:
        self._writer.add_message(channel_id, log_time, data, publish_time, sequence)
        self._tee.add_message(channel_id, log_time, data)  # type: ignore[union-attr]
