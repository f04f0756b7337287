"""The sans-IO decoder: CAN frames and stream chunks in, events out, per-source state kept."""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

from analyzer.protocol.bus_state import BusState
from analyzer.protocol.can_error import decode_error_frame
from analyzer.protocol.codec import decode_command
from analyzer.protocol.event_columns import ColumnSlots, EventColumns
from analyzer.protocol.frame_columns import FrameColumns
from analyzer.protocol.lru import MAX_SOURCES, LruTable
from analyzer.protocol.reassembly import FeedbackReassembler, message_events
from analyzer.protocol.routes import COMMAND, FEEDBACK, ROUTES, STATUS_TOPICS, TEXT
from analyzer.protocol.types import (
    BAD_FRAME,
    BUS_ERROR,
    TOPIC_CAN_BUS_STATE,
    TOPIC_CAN_OTHER,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    CanFrame,
    Event,
    StreamChunk,
    diagnostic,
    hexstr,
)
from analyzer.protocol.uav import TextAssembler, decode_status

if TYPE_CHECKING:  # streams are framed by modules imported when one comes
    from analyzer.protocol.framing import RawFrame, StreamFramer

__all__ = ["STATUS_TOPICS", "ProtocolDecoder"]

# The extra fields of a plain CAN frame: none. Shared and never written to.
NO_EXTRA: dict[str, Any] = {}


class ProtocolDecoder:
    """Decodes everything of the protocol from any mix of CAN frames and stream chunks.

    State (feedback reassembly, text messages, stream framing) is kept per CAN channel
    and per stream source + direction, for at most ``max_sources`` of each at once: a
    new one beyond that closes the least recently used, whose partial messages become
    diagnostics that say why (``sources_given_up`` counts them). The decoder never raises
    on any input and never reads a clock: times come with the input, ``tick(now)``
    reports stale partial messages in live use, ``close()`` flushes everything at the
    end of input.
    """

    def __init__(
        self, *, emit_other: bool = False, text_limit: int = 256, max_sources: int = MAX_SOURCES
    ) -> None:
        self.emit_other = emit_other
        self.text_limit = text_limit
        self.max_sources = max_sources
        self._reassemblers: LruTable[str, FeedbackReassembler] = LruTable(
            self._evict_reassembler, max_sources
        )
        self._texts: LruTable[str, TextAssembler] = LruTable(self._evict_text, max_sources)
        self._framers: LruTable[tuple[str, str], StreamFramer] = LruTable(
            self._evict_framer, max_sources
        )
        # Each CAN channel's controller state, followed from its error frames.
        self._buses: LruTable[str, BusState] = LruTable(_forget, max_sources)
        self._given_up: list[Event] = []  # diagnostics of evicted state, for the caller
        # The reassembler used last (only an add for another source can evict it).
        self._recent_source: str | None = None
        self._recent: FeedbackReassembler | None = None
        self._retired = {"bytes_fed": 0, "bytes_framed": 0, "bytes_discarded": 0}
        self.frames = 0
        self.protocol_frames = 0
        self.other_frames = 0
        self.chunks = 0
        self.last_time = 0.0

    # -- input ---------------------------------------------------------------------------------

    def feed(self, item: CanFrame | StreamChunk) -> list[Event]:
        if isinstance(item, CanFrame):
            return self.feed_can(item)
        return self.feed_stream(item)

    def feed_can(self, frame: CanFrame) -> list[Event]:
        """Decode one CAN frame (from a bus or a log)."""
        events: list[Event] = []
        self.feed_batch((frame,), events)
        return events

    def feed_batch(
        self,
        items: Iterable[object],
        events: list[Event],
        columns: ColumnSlots | None = None,
    ) -> None:
        """Decode a batch in order: what frames and chunks give goes to ``events``, and
        ready-made events (diagnostics of a reader) go there as they are.

        Every CAN frame goes through the one dispatch (``_frame``). A block of frames as
        columns (``FrameColumns``) is decoded in vectors (``decode_columns``); its events
        go to ``columns`` with their place in ``events`` (made into Events at once when
        ``columns`` is None).
        """
        frame_events = self._frame
        extend = events.extend
        for item in items:
            if isinstance(item, CanFrame):
                self.frames += 1
                self.last_time = item.time
                extend(frame_events(item, item.channel or "can", NO_EXTRA))
            elif isinstance(item, FrameColumns):
                decoded = self.decode_columns(item)
                if columns is None:
                    extend(decoded.events())
                else:
                    columns.append((len(events), decoded))
            elif isinstance(item, StreamChunk):
                extend(self.feed_stream(item))
            elif isinstance(item, Event):
                events.append(item)

    def decode_columns(self, frames: FrameColumns) -> EventColumns:
        """A block of frames as columns, decoded in vectors (``vector_decode``): the same
        events, and the same state and counters after it, as frame by frame."""
        from analyzer.protocol.vector_decode import feedback_groups, plan_columns

        out = EventColumns()
        if not len(frames):
            return out
        crowded = self._crowded(len(frames.channels))
        plan = plan_columns(frames, crowded=crowded, emit_other=self.emit_other)
        out.groups += plan.groups
        for source, rows, whole, regular in plan.feedback:
            self.last_time = float(frames.time[rows[0]])
            reassembler = self._reassembler(source)
            taken, fed = reassembler.feed_segments(
                frames.time[rows].tolist(),
                frames.data[rows].tobytes(),
                frames.length[rows].tolist(),
                whole,
                regular,
            )
            groups, messages = feedback_groups(frames, rows, taken, source)
            out.groups += groups
            for row, message in messages:  # messages the vectors left (with a warning)
                out.add(row, message_events(source, [message], NO_EXTRA))
            for index, results in fed:
                out.add(int(rows[index]), message_events(source, results, NO_EXTRA))
        for source in plan.feedback_order:  # the least recently used first, as frame by frame
            self._reassembler(source)
        for row in plan.scalar.tolist():
            frame = frames.frame(row)
            self.last_time = frame.time
            out.add(row, self._frame(frame, frame.channel or "can", NO_EXTRA))
        self.frames += len(frames)
        self.protocol_frames += plan.protocol_rows
        self.other_frames += plan.other_rows
        self.last_time = float(frames.time[-1])
        return out

    def feed_stream(self, chunk: StreamChunk) -> list[Event]:
        """Decode bytes read from a TCP / UART stream."""
        self.chunks += 1
        self.last_time = chunk.time
        key = (chunk.source, chunk.direction)
        framer = self._framers.get(key)
        if framer is None:
            from analyzer.protocol.framing import StreamFramer

            framer = self._framers.add(key, StreamFramer(chunk.source, chunk.direction))
            if self._given_up:
                return self._take_given_up() + self._framed(
                    framer, framer.feed(chunk.data, chunk.time)
                )
        return self._framed(framer, framer.feed(chunk.data, chunk.time))

    def tick(self, now: float) -> list[Event]:
        """Live use: report partial messages that waited too long."""
        out: list[Event] = []
        for reassembler in self._reassemblers.values():
            out.extend(message_events(reassembler.source, reassembler.tick(now), {}))
        for text in self._texts.values():
            out.extend(text.tick(now))
        for framer in self._framers.values():
            out.extend(self._framed(framer, framer.tick(now)))
        return out

    def close(self, now: float | None = None) -> list[Event]:
        """End of input: everything still pending becomes a diagnostic."""
        when = self.last_time if now is None else now
        out: list[Event] = []
        for framer in self._framers.values():
            out.extend(self._framed(framer, framer.close(when)))
        for reassembler in self._reassemblers.values():
            out.extend(message_events(reassembler.source, reassembler.close(when), {}))
        for text in self._texts.values():
            out.extend(text.close(when))
        return out

    @property
    def stats(self) -> dict[str, int]:
        parts: list[Any] = [*self._framers.values(), *self._reassemblers.values()]
        retired = self._retired
        stats = {
            "frames": self.frames,
            "protocol_frames": self.protocol_frames,
            "other_frames": self.other_frames,
            "chunks": self.chunks,
            "bytes_fed": retired["bytes_fed"] + sum(p.bytes_fed for p in parts),
            "bytes_framed": retired["bytes_framed"] + sum(p.bytes_framed for p in parts),
            "bytes_discarded": retired["bytes_discarded"] + sum(p.bytes_discarded for p in parts),
            "bytes_pending": sum(p.pending for p in parts),
        }
        given_up = self._reassemblers.evicted + self._texts.evicted + self._framers.evicted
        if given_up:
            stats["sources_given_up"] = given_up
        return stats

    # -- bounded per-source state ----------------------------------------------------------------

    def _take_given_up(self) -> list[Event]:
        events, self._given_up = self._given_up, []
        return events

    def _give_up(self, events: list[Event]) -> None:
        why = (
            f"given up early: more than {self.max_sources} sources at once, "
            "this one was the least recently used"
        )
        for event in events:
            detail = str(event.fields.get("detail", ""))
            if event.topic == TOPIC_DIAGNOSTICS and why not in detail:
                event.fields["detail"] = f"{detail} ({why})"
        self._given_up.extend(events)

    def _retire(self, part: FeedbackReassembler | StreamFramer) -> None:
        retired = self._retired
        retired["bytes_fed"] += part.bytes_fed
        retired["bytes_framed"] += part.bytes_framed
        retired["bytes_discarded"] += part.bytes_discarded

    def _evict_reassembler(self, source: str, reassembler: FeedbackReassembler) -> None:
        self._give_up(message_events(source, reassembler.close(self.last_time), {}))
        self._retire(reassembler)

    def _evict_text(self, source: str, text: TextAssembler) -> None:
        self._give_up(text.close(self.last_time))

    def _evict_framer(self, key: tuple[str, str], framer: StreamFramer) -> None:
        self._give_up(self._framed(framer, framer.close(self.last_time)))
        self._retire(framer)

    # -- CAN -------------------------------------------------------------------------------------

    def _crowded(self, new_sources: int) -> bool:
        """Whether ``new_sources`` more sources could make a table give one up (then a block
        of columns goes frame by frame, where each eviction happens in its place)."""
        tables = (len(self._reassemblers), len(self._texts), len(self._buses))
        return max(tables) + new_sources >= self.max_sources

    def _reassembler(self, source: str) -> FeedbackReassembler:
        if source == self._recent_source and self._recent is not None:
            return self._recent  # still the most recently used: no reordering needed
        reassembler = self._reassemblers.get(source)
        if reassembler is None:
            reassembler = self._reassemblers.add(source, FeedbackReassembler(source))
        self._recent_source, self._recent = source, reassembler
        return reassembler

    def _frame(self, frame: CanFrame, source: str, extra: dict[str, Any]) -> list[Event]:
        """The one dispatch of a CAN frame (``routes``): error frames, other devices,
        commands, feedback segments, text and status frames; ``extra`` fields go into
        every event (a stream's transport and direction)."""
        if frame.is_error:
            return self._bus_error(frame, source, extra)
        can_id = frame.can_id
        route = ROUTES.get(can_id)
        if route is None:
            self.other_frames += 1
            if not self.emit_other:
                return []
            return [
                Event(
                    TOPIC_CAN_OTHER,
                    frame.time,
                    source,
                    {
                        "can_id": can_id,
                        "extended": frame.extended,
                        "dlc": frame.dlc,
                        "data": hexstr(frame.data),
                        "remote": frame.is_remote,
                        **extra,
                    },
                )
            ]
        self.protocol_frames += 1
        if frame.is_remote:
            return [
                diagnostic(
                    frame.time,
                    source,
                    BAD_FRAME,
                    f"remote frame on protocol ID 0x{can_id:08X}",
                    frame.data,
                    can_id=can_id,
                    **extra,
                )
            ]
        warnings: list[str] = []
        if not frame.extended:
            warnings.append(
                f"standard (11-bit) frame on ID 0x{can_id:X}; the protocol uses extended IDs"
            )
        if frame.is_fd:
            warnings.append("CAN FD frame; the protocol uses classic CAN")
        if route == COMMAND:
            fields, more = decode_command(frame.data)
            if extra:
                fields.update(extra)
            return [Event(TOPIC_COMMAND, frame.time, source, fields, warnings + more)]
        if route == FEEDBACK:
            results = self._reassembler(source).feed(frame.data, frame.time)
            dropped = self._take_given_up() if self._given_up else []
            if not results:
                return dropped
            return dropped + message_events(source, results, extra, warnings)
        if route == TEXT:
            text = self._texts.get(source)
            given_up: list[Event] = []
            if text is None:
                text = self._texts.add(source, TextAssembler(source, self.text_limit))
                given_up = self._take_given_up()
            events = text.feed(can_id, frame.data, frame.time)
            for event in events:
                event.warnings[:0] = warnings
                event.fields.update(extra)
            return given_up + events if given_up else events
        fields, more = decode_status(can_id, frame.data)
        fields["raw"] = hexstr(frame.data)
        if extra:
            fields.update(extra)
        return [Event(STATUS_TOPICS[can_id], frame.time, source, fields, warnings + more)]

    def _bus_error(self, frame: CanFrame, source: str, extra: dict[str, Any]) -> list[Event]:
        """An error frame: a bus_error diagnostic, and the channel's state when it is due."""
        error = decode_error_frame(frame.can_id, frame.data)
        bus = self._buses.get(source) or self._buses.add(source, BusState())
        due = bus.note(error, frame.time)
        if error.problems:
            detail = f"malformed CAN error frame ({'; '.join(error.problems)}): {error.text}"
        else:
            detail = f"CAN error frame: {error.text}"
        events = [
            diagnostic(
                frame.time,
                source,
                BUS_ERROR,
                f"{detail}; bus {bus.state}",
                frame.data,
                can_id=frame.can_id,
                **error.fields(),
                bus_state=bus.state,
                **extra,
            )
        ]
        if due:
            events.append(Event(TOPIC_CAN_BUS_STATE, frame.time, source, bus.message()))
        return events

    # -- streams ---------------------------------------------------------------------------------

    def _framed(self, framer: StreamFramer, results: list[RawFrame | Event]) -> list[Event]:
        from analyzer.protocol.stream_frames import stream_frame_events

        out: list[Event] = []
        extra: dict[str, Any] = {"direction": framer.direction} if framer.direction else {}
        source = framer.source
        for result in results:
            if isinstance(result, Event):
                out.append(result)
            else:
                out.extend(stream_frame_events(result, source, extra, self._frame))
        return out


def _forget(source: str, bus: BusState) -> None:
    """A channel's bus state given up for a newer channel: nothing is pending in it."""
