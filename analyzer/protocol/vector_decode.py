"""The decoder's columnar path: a block of frames (``FrameColumns``) decoded in vectors.

Commands and UAV status frames are grouped by layout and decoded a column at a time
(``vector_layouts``); a row that would give a warning is decoded by the scalar decoder.
The 4-segment feedback of each channel is grouped in vectors too: a message whose four
segments follow each other with a header, a CRC-16/MODBUS that checks and no late
segment is taken whole while the reassembler is idle; any other segment goes through
the channel's reassembler, in order, so that reordered, missing, repeated and damaged
segments give the diagnostics they always give. Every other frame (text, standard IDs
on protocol IDs, other devices) goes through the scalar decoder in frame order. Each
event is placed at the row of the frame that gave it (``EventColumns``), so the events
come out in the order and with the contents the frame-by-frame decoder gives.
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
import numpy.typing as npt

from analyzer.protocol.crc import _TABLE
from analyzer.protocol.event_columns import EventColumns, EventGroup
from analyzer.protocol.feedback import FRAME_SIZES
from analyzer.protocol.frame_columns import FrameColumns
from analyzer.protocol.ids import CONTROL_ID, FEEDBACK_ID, HEADER
from analyzer.protocol.reassembly import SEGMENTS_PER_MESSAGE, Message
from analyzer.protocol.uav import STATUS_FRAMES
from analyzer.protocol.vector_layouts import VectorLayout, command_layouts, status_layout

if TYPE_CHECKING:
    from analyzer.protocol.lru import LruTable
    from analyzer.protocol.reassembly import FeedbackReassembler
    from analyzer.protocol.types import CanFrame, Event


class Decoder(Protocol):
    """The decoder whose state the columnar path moves on (``protocol.decoder.Decoder``)."""

    frames: int
    protocol_frames: int
    last_time: float
    max_sources: int
    _reassemblers: LruTable[str, FeedbackReassembler]
    _given_up: list[Event]

    def feed_batch(self, items: Any, raw: list[Any], events: list[Event]) -> None: ...
    def _reassembler(self, source: str) -> FeedbackReassembler: ...
    def _take_given_up(self) -> list[Event]: ...
    def _feedback(self, source: str, results: list[Any], extra: dict[str, Any]) -> list[Event]: ...
    def _can_any(self, frame: CanFrame, source: str, extra: dict[str, Any]) -> list[Event]: ...


Array = npt.NDArray[Any]

_CRC = np.array(_TABLE, np.int64)
_SIZES = np.zeros(256, np.int64)  # message size by length byte (0: no feedback layout)
for _k, _v in FRAME_SIZES.items():
    _SIZES[_k] = _v
_NO_EXTRA: dict[str, Any] = {}


def decode_columns(decoder: Decoder, frames: FrameColumns) -> EventColumns:
    """Decode ``frames`` into events; the decoder's state and counters move on as if it
    had been given each frame in turn."""
    out = EventColumns()
    n = len(frames)
    if not n:
        return out
    can_id, extended, length = frames.can_id, frames.extended, frames.length
    eight = extended & (length == 8)
    command = eight & (can_id == CONTROL_ID)
    feedback = extended & (can_id == FEEDBACK_ID)
    status = eight & np.isin(can_id, np.fromiter(STATUS_FRAMES, np.int64))
    single = ~(command | feedback | status)
    if decoder.max_sources <= len(frames.channels) + len(decoder._reassemblers):
        single[:] = True  # channels beyond the limit: the scalar decoder gives some up
        command[:] = feedback[:] = status[:] = False
    if command.any():
        _commands(decoder, frames, np.flatnonzero(command), out)
    if status.any():
        _statuses(decoder, frames, np.flatnonzero(status), out)
    if feedback.any():
        for channel in np.unique(frames.channel[feedback]).tolist():
            rows = np.flatnonzero(feedback & (frames.channel == channel))
            _feedback(decoder, frames, rows, frames.channels[channel], out)
    for row in np.flatnonzero(single).tolist():
        frame = frames.frame(row)
        decoder.last_time = frame.time
        out.add(row, decoder._can_any(frame, frame.channel or "can", _NO_EXTRA))
    decoder.frames += n
    decoder.protocol_frames += int(np.count_nonzero(~single))
    decoder.last_time = float(frames.time[-1])
    return out


def _scalar(decoder: Decoder, frames: FrameColumns, rows: Array, out: EventColumns) -> None:
    """Rows decoded one by one (they give warnings): as the scalar decoder decodes them."""
    for row in rows.tolist():
        frame = frames.frame(row)
        events: list[Any] = []
        decoder.feed_batch((frame,), [], events)
        decoder.frames -= 1  # counted with the block
        decoder.protocol_frames -= 1
        out.add(row, events)


def _group(layout: VectorLayout, frames: FrameColumns, rows: Array, out: EventColumns) -> Array:
    """Decode the clean ``rows`` of ``layout`` in vectors; the rows left (with warnings)."""
    data = frames.data[rows]
    clean = layout.clean(data)
    taken = rows[clean]
    if taken.shape[0]:
        names = frames.channels
        channel = frames.channel[taken]
        first = int(channel[0])
        if (channel == first).all():
            sources = [names[first] or "can"] * int(taken.shape[0])
        else:
            sources = [names[c] or "can" for c in channel.tolist()]
        clean_data = data[clean]
        out.groups.append(
            EventGroup(
                layout.topic,
                taken,
                frames.time[taken],
                sources,
                layout.keys,
                layout.constants,
                functools.partial(layout.values, clean_data),
                layout.name,
            )
        )
    return rows[~clean]


def _commands(decoder: Decoder, frames: FrameColumns, rows: Array, out: EventColumns) -> None:
    data = frames.data[rows]
    keys = data[:, 0].astype(np.int64) << 8 | data[:, 1]
    left: list[Array] = []
    for key in np.unique(keys).tolist():
        mine = rows[keys == key]
        layouts = command_layouts(key)
        if layouts is None:
            left.append(mine)
            continue
        if None in layouts:
            left.append(_group(layouts[None], frames, mine, out))
            continue
        row = next(iter(layouts.values())).fields[0]  # the selector
        selectors = frames.data[mine, row.offset]
        for value in np.unique(selectors).tolist():
            same = mine[selectors == value]
            layout = layouts.get(value)
            left.append(same if layout is None else _group(layout, frames, same, out))
    if left:
        _scalar(decoder, frames, np.sort(np.concatenate(left)), out)


def _statuses(decoder: Decoder, frames: FrameColumns, rows: Array, out: EventColumns) -> None:
    ids = frames.can_id[rows]
    left = [
        _group(status_layout(can_id), frames, rows[ids == can_id], out)
        for can_id in np.unique(ids).tolist()
    ]
    rest = np.concatenate(left)
    if rest.shape[0]:
        _scalar(decoder, frames, np.sort(rest), out)


def crc16_rows(messages: Array, sizes: Array) -> Array:
    """CRC-16/MODBUS of each row of ``messages`` over its first ``sizes`` bytes."""
    crc = np.full(messages.shape[0], 0xFFFF, np.int64)
    for column in range(int(sizes.max(initial=0))):
        step = (crc >> 8) ^ _CRC[(crc ^ messages[:, column]) & 0xFF]
        crc = np.where(column < sizes, step, crc)
    return crc


def clean_messages(times: Array, data: Array, lengths: Array, late_after: float) -> Array:
    """Which segments start a message the reassembler takes whole, with no warning: four
    8-byte segments in a row, a header first, no gap over ``late_after``, the CRC right."""
    n = data.shape[0]
    starts = np.zeros(n, bool)
    if n < SEGMENTS_PER_MESSAGE:
        return starts
    m = n - SEGMENTS_PER_MESSAGE + 1
    size = _SIZES[data[:m, 2]]
    ok = (data[:m, 0] == HEADER[0]) & (data[:m, 1] == HEADER[1]) & (size > 0)
    for k in range(SEGMENTS_PER_MESSAGE):
        ok &= lengths[k : k + m] == 8
    for k in range(1, SEGMENTS_PER_MESSAGE):
        ok &= (times[k : k + m] - times[k - 1 : k - 1 + m]) <= late_after
    candidates = np.flatnonzero(ok)
    if candidates.shape[0]:
        message = np.concatenate([data[candidates + k] for k in range(4)], axis=1)
        message = message.astype(np.int64)
        sizes = size[candidates]
        crc = crc16_rows(message, sizes - 2)
        rows = np.arange(candidates.shape[0])
        wire = message[rows, sizes - 2] | message[rows, sizes - 1] << 8
        starts[candidates[crc == wire]] = True
    return starts


def _feedback(
    decoder: Decoder, frames: FrameColumns, rows: Array, channel: str, out: EventColumns
) -> None:
    """The feedback segments of one channel, in order (see the module docstring)."""
    source = channel or "can"
    decoder.last_time = float(frames.time[rows[0]])
    reassembler = decoder._reassembler(source)
    if decoder._given_up:
        out.add(int(rows[0]), decoder._take_given_up())
    times = frames.time[rows]
    data = frames.data[rows]
    late = reassembler.late_after
    clean = clean_messages(times, data, frames.length[rows], late).tolist()
    time_list = times.tolist()
    row_list = rows.tolist()
    blob = data.tobytes()
    sizes = frames.length[rows].tolist()
    feed = reassembler.feed
    j, n = 0, len(row_list)
    while j < n:
        t = time_list[j]
        if (
            clean[j]
            and not reassembler._pending
            and not (
                reassembler._last_tail
                and t - reassembler._last_tail_time <= late
                and blob[8 * j : 8 * j + 8] == reassembler._last_tail
            )
        ):
            end = j + SEGMENTS_PER_MESSAGE - 1
            message = blob[8 * j : 8 * end + 8]
            reassembler.bytes_fed += 32
            reassembler.bytes_framed += 32
            reassembler._last_tail = message[24:]
            reassembler._last_tail_time = time_list[end]
            done = Message(time_list[end], message, ())
            out.add(row_list[end], decoder._feedback(source, [done], _NO_EXTRA))
            j = end + 1
            continue
        decoder.last_time = t
        results = feed(blob[8 * j : 8 * j + sizes[j]], t)
        if results:
            out.add(row_list[j], decoder._feedback(source, results, _NO_EXTRA))
        j += 1
