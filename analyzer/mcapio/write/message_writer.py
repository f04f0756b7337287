"""Raw items and decoded events of a batch as MCAP messages, in time order, with their views."""

from __future__ import annotations

import operator
from collections.abc import Sequence

from analyzer.mcapio.channels import (
    FRAME_TAILS,
    ROLE_EVENT,
    ROLE_RAW,
    ROLE_VIEW,
    TOPIC_CAN_FRAMES,
    TOPIC_STREAM_BYTES,
    TRUE_FALSE,
    MessageTee,
    can_frame_json,
    frame_tail,
    json_bytes,
    stream_chunk_json,
)
from analyzer.mcapio.foxglove import VIEW_INPUT_TOPICS, FoxgloveViews
from analyzer.mcapio.log_time import MAX_LOG_SECONDS, time_ns
from analyzer.mcapio.write.channel_registry import ChannelRegistry
from analyzer.mcapio.write.chunked_writer import ChunkedWriter
from analyzer.pipeline import RawItem
from analyzer.protocol.types import CanFrame, Event
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
        self.items_written = 0
        self.events_written = 0
        self.messages_written = 0
        self.last_time: float | None = None
        self.dirty = False  # written since the last flush

    def write_batch(self, items: list[RawItem], events: list[Event]) -> None:
        """Items and events of one batch, merged in time order (an item before its events)."""
        if not events or (items and items[-1].time <= events[0].time):
            self._put([*items, *events])
        elif not items:
            self._put(events)
        else:
            self._put(sorted([*items, *events], key=_time_of))
        self.tally.add_items(items)
        self.tally.add_events(events)

    def write_items(self, items: list[RawItem]) -> None:
        self._put(items)
        self.tally.add_items(items)

    def write_events(self, events: list[Event]) -> None:
        self._put(events)
        self.tally.add_events(events)

    def _put(self, messages: Sequence[RawItem | Event]) -> None:
        """Each raw item to its lossless channel, each event to its topic's channel (and its
        views), in the order given: one loop, as this runs for every frame of a file."""
        if not messages:
            return
        add = self._writer.add_message if self._tee is None else self._add_teed
        registry = self._registry
        sequence = registry.sequence
        channels = registry.ids
        views = self._views
        can_id = channels.get(TOPIC_CAN_FRAMES, 0)
        tails = FRAME_TAILS
        items = events = extra = 0
        for message in messages:
            kind = type(message)
            if kind is Event:
                event: Event = message  # type: ignore[assignment]
                topic = event.topic
                channel_id = channels.get(topic) or registry.channel(topic, ROLE_EVENT)
                t = event.time
                log_time = round(t * 1e9) if 0 < t < MAX_LOG_SECONDS else time_ns(t)
                number = sequence[channel_id] + 1
                sequence[channel_id] = number
                add(channel_id, log_time, json_bytes(event.to_dict()), log_time, number)
                events += 1
                if views is not None and topic in VIEW_INPUT_TOPICS:
                    for view_topic, view in views.views(event):
                        view_id = channels.get(view_topic)
                        view_id = view_id or registry.channel(view_topic, ROLE_VIEW)
                        number = sequence[view_id] + 1
                        sequence[view_id] = number
                        add(view_id, log_time, json_bytes(view), log_time, number)
                        extra += 1
                continue
            if kind is CanFrame:
                channel_id = can_id or registry.channel(TOPIC_CAN_FRAMES, ROLE_RAW)
                can_id = channel_id
                frame: CanFrame = message  # type: ignore[assignment]
                t = frame.time
                if type(t) is float and t - t == 0:  # can_frame_json, inlined: every frame
                    key = (
                        frame.channel,
                        frame.is_remote,
                        frame.is_error,
                        frame.is_fd,
                        frame.direction,
                    )
                    tail = tails.get(key) or frame_tail(frame)
                    data = (
                        f'{{"time":{t!r},"id":{frame.can_id},"extended":'
                        f'{TRUE_FALSE[frame.extended]},"dlc":{frame.dlc},'
                        f'"data":"{frame.data.hex(" ").upper()}{tail}'
                    ).encode()
                else:
                    data = can_frame_json(frame)
            else:
                topic = TOPIC_STREAM_BYTES
                channel_id = channels.get(topic) or registry.channel(topic, ROLE_RAW)
                data = stream_chunk_json(message)  # type: ignore[arg-type]
            t = message.time
            log_time = round(t * 1e9) if 0 < t < MAX_LOG_SECONDS else time_ns(t)
            number = sequence[channel_id] + 1
            sequence[channel_id] = number
            add(channel_id, log_time, data, log_time, number)
            items += 1
        self.items_written += items
        self.events_written += events
        self.messages_written += items + events + extra
        self.dirty = True
        self.last_time = messages[-1].time

    def _add_teed(
        self, channel_id: int, log_time: int, data: bytes, publish_time: int, sequence: int
    ) -> None:
        self._writer.add_message(channel_id, log_time, data, publish_time, sequence)
        self._tee.add_message(channel_id, log_time, data)  # type: ignore[union-attr]
