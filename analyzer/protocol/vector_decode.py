"""The decoder's columnar path: a block of frames (``FrameColumns``) decoded in vectors.

Stateless: ``plan_columns`` routes each row by the decoder's routing table (``routes``)
and decodes what needs no state in vectors: commands and UAV status frames grouped by
layout (``vector_layouts``; a row that would give a warning is left to the one
frame-by-frame dispatch, which says what is wrong), and the frames of other devices
(counted, or one group of ``/can/other`` events). The feedback segments of each channel
are grouped, and ``clean_messages`` marks where four segments in a row make a message
with a header, a CRC-16/MODBUS that checks and no late segment; the decoder's
reassembler takes those whole (``FeedbackReassembler.feed_segments``) and
``feedback_groups`` decodes them in vectors. Every other row (text, protocol IDs sent
as standard frames, odd lengths) goes to the frame-by-frame dispatch, in frame order.
Each event keeps the row of the frame that gave it (``EventColumns``), so the events
come out in the order and with the contents frame by frame decoding gives.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from analyzer.protocol.arrays import distinct
from analyzer.protocol.crc import _TABLE
from analyzer.protocol.event_columns import EventGroup
from analyzer.protocol.feedback import FRAME_SIZES
from analyzer.protocol.frame_columns import FrameColumns
from analyzer.protocol.ids import HEADER
from analyzer.protocol.reassembly import LATE_AFTER_S, SEGMENTS_PER_MESSAGE, Message
from analyzer.protocol.routes import COMMAND, FEEDBACK, ROUTES, STATUS
from analyzer.protocol.types import TOPIC_CAN_OTHER
from analyzer.protocol.vector_layouts import (
    VectorLayout,
    command_layouts,
    feedback_layout,
    hex_rows,
    status_layout,
)

Array = npt.NDArray[Any]

_CRC = np.array(_TABLE, np.int64)
_SIZES = np.zeros(256, np.int64)  # message size by length byte (0: no feedback layout)
for _k, _v in FRAME_SIZES.items():
    _SIZES[_k] = _v
_ROUTED = np.array(sorted(ROUTES), np.int64)
_ROUTE_NAMES = sorted(set(ROUTES.values()))
_ROUTE_OF = np.array([_ROUTE_NAMES.index(ROUTES[i]) for i in sorted(ROUTES)], np.int8)
_OTHER_KEYS = ("can_id", "extended", "dlc", "data", "remote")


@dataclass(slots=True)
class ColumnPlan:
    """A block routed: ``groups`` decoded in vectors; per channel with feedback its
    source, rows, which rows start a clean message and how many clean messages come one
    after the other from the first row (``regular_messages``); the rows for the frame-by-frame
    dispatch (ascending); how many rows were protocol frames taken here (groups and
    feedback) and frames of other devices; the channels with feedback, the one whose
    last segment came first first."""

    groups: list[EventGroup] = field(default_factory=list)
    feedback: list[tuple[str, Array, list[bool], int]] = field(default_factory=list)
    scalar: Array = field(default_factory=lambda: np.zeros(0, np.int64))
    protocol_rows: int = 0
    other_rows: int = 0
    feedback_order: list[str] = field(default_factory=list)


def plan_columns(frames: FrameColumns, *, crowded: bool, emit_other: bool) -> ColumnPlan:
    """Route the rows of ``frames`` and decode the stateless ones (see the module
    docstring). ``crowded``: the decoder could give up a source's state in this block,
    so every row goes frame by frame, where each eviction happens in its place."""
    plan = ColumnPlan()
    n = len(frames)
    if crowded:
        plan.scalar = np.arange(n)
        return plan
    can_id, extended, length = frames.can_id, frames.extended, frames.length
    # Each row's route (an index into _ROUTE_NAMES; -1: other devices), in two passes.
    route = np.full(n, -1, np.int8)
    routed = np.isin(can_id, _ROUTED)
    route[routed] = _ROUTE_OF[np.searchsorted(_ROUTED, can_id[routed])]
    eight = extended & (length == 8)
    command = eight & (route == _ROUTE_NAMES.index(COMMAND))
    feedback = extended & (route == _ROUTE_NAMES.index(FEEDBACK))
    status = eight & (route == _ROUTE_NAMES.index(STATUS))
    other = ~routed
    left = [np.flatnonzero(~(command | feedback | status | other))]
    if command.any():
        left += _commands(frames, np.flatnonzero(command), plan.groups)
    if status.any():
        ids = can_id[status]
        rows = np.flatnonzero(status)
        for value in distinct(ids).tolist():
            left.append(_group(status_layout(value), frames, rows[ids == value], plan.groups))
    if feedback.any():
        last_rows: list[tuple[int, str]] = []
        for channel in distinct(frames.channel[feedback]).tolist():
            rows = np.flatnonzero(feedback & (frames.channel == channel))
            times, data = frames.time[rows], frames.data[rows]
            whole = clean_messages(times, data, frames.length[rows])
            source = frames.channels[channel] or "can"
            regular = regular_messages(whole, data, times)
            plan.feedback.append((source, rows, whole.tolist(), regular))
            last_rows.append((int(rows[-1]), source))
        plan.feedback_order = [source for _, source in sorted(last_rows)]
    plan.other_rows = int(np.count_nonzero(other))
    if emit_other and plan.other_rows:
        plan.groups.append(_other_group(frames, np.flatnonzero(other)))
    plan.scalar = np.sort(np.concatenate(left))
    plan.protocol_rows = n - plan.other_rows - int(plan.scalar.shape[0])
    return plan


def feedback_groups(
    frames: FrameColumns, rows: Array, taken: list[int], source: str
) -> tuple[list[EventGroup], list[tuple[int, Message]]]:
    """The messages the reassembler took whole (they start at ``rows[taken]``), decoded
    in vectors; those that would give a warning come back as Messages at their last
    segment's row, for the scalar decoder."""
    if not taken:
        return [], []
    first = np.array(taken, np.int64)
    ends = rows[first + SEGMENTS_PER_MESSAGE - 1]
    parts = [frames.data[rows[first + k]] for k in range(SEGMENTS_PER_MESSAGE)]
    messages = np.concatenate(parts, axis=1)
    groups: list[EventGroup] = []
    left: list[tuple[int, Message]] = []
    kinds = messages[:, 2]
    for length_byte in distinct(kinds).tolist():
        mine = np.flatnonzero(kinds == length_byte)
        layout = feedback_layout(length_byte)
        data = messages[mine]
        clean = layout.clean(data)
        if clean.any():
            done = mine[clean]
            groups.append(_event_group(layout, data[clean], ends[done], frames, [source]))
        times = frames.time[ends]
        for i in mine[~clean].tolist():
            message = messages[i].tobytes()
            left.append((int(ends[i]), Message(float(times[i]), message, ())))
    return groups, left


def _event_group(
    layout: VectorLayout, data: Array, rows: Array, frames: FrameColumns, sources: list[str]
) -> EventGroup:
    """The events of clean ``data`` at ``rows`` (``sources``: one for all, or one a row)."""
    if len(sources) == 1:
        sources = sources * int(rows.shape[0])
    return EventGroup(
        layout.topic,
        rows,
        frames.time[rows],
        sources,
        layout.keys,
        layout.constants,
        functools.partial(layout.values, data),
        layout.name,
    )


def _sources(frames: FrameColumns, rows: Array) -> list[str]:
    """The source of each of ``rows``: its channel's name, or ``can`` for none."""
    names = frames.channels
    channel = frames.channel[rows]
    first = int(channel[0])
    if (channel == first).all():
        return [names[first] or "can"] * int(rows.shape[0])
    return [names[c] or "can" for c in channel.tolist()]


def _group(layout: VectorLayout, frames: FrameColumns, rows: Array, out: list[EventGroup]) -> Array:
    """Decode the clean ``rows`` of ``layout`` in vectors; the rows left (with warnings)."""
    data = frames.data[rows]
    clean = layout.clean(data)
    taken = rows[clean]
    if taken.shape[0]:
        out.append(_event_group(layout, data[clean], taken, frames, _sources(frames, taken)))
    return rows[~clean]


def _commands(frames: FrameColumns, rows: Array, out: list[EventGroup]) -> list[Array]:
    """The command rows grouped by command and selector value; the rows left."""
    data = frames.data[rows]
    keys = data[:, 0].astype(np.int64) << 8 | data[:, 1]
    left: list[Array] = []
    for key in distinct(keys).tolist():
        mine = rows[keys == key]
        layouts = command_layouts(key)
        if layouts is None:
            left.append(mine)
            continue
        if None in layouts:
            left.append(_group(layouts[None], frames, mine, out))
            continue
        selector = next(iter(layouts.values())).fields[0]
        values = frames.data[mine, selector.offset]
        for value in distinct(values).tolist():
            same = mine[values == value]
            layout = layouts.get(value)
            left.append(same if layout is None else _group(layout, frames, same, out))
    return left


def _other_group(frames: FrameColumns, rows: Array) -> EventGroup:
    """The frames of other devices as ``/can/other`` events (``--raw``)."""
    lengths = frames.length[rows]

    def values() -> dict[str, list[Any]]:
        text = hex_rows(frames.data[rows])
        sizes = (3 * lengths.astype(np.int64) - 1).clip(0).tolist()
        return {
            "can_id": frames.can_id[rows].tolist(),
            "extended": frames.extended[rows].tolist(),
            "dlc": lengths.tolist(),
            "data": [t[:s] for t, s in zip(text, sizes, strict=True)],
        }

    return EventGroup(
        TOPIC_CAN_OTHER,
        rows,
        frames.time[rows],
        _sources(frames, rows),
        _OTHER_KEYS,
        {"remote": False},
        values,
    )


def regular_messages(
    whole: Array, data: Array, times: Array, late_after: float = LATE_AFTER_S
) -> int:
    """How many clean messages (``clean_messages``) follow each other from segment 0, no
    one starting with a repeat of the segment that ends the one before (a segment equal
    to it within ``late_after``, which the reassembler reports as repeated)."""
    starts = whole[::SEGMENTS_PER_MESSAGE][: whole.shape[0] // SEGMENTS_PER_MESSAGE].copy()
    m = starts.shape[0]
    if m > 1:
        words = np.ascontiguousarray(data).view("<u8").ravel()
        first = slice(SEGMENTS_PER_MESSAGE, SEGMENTS_PER_MESSAGE * m, SEGMENTS_PER_MESSAGE)
        last = slice(SEGMENTS_PER_MESSAGE - 1, SEGMENTS_PER_MESSAGE * m - 1, SEGMENTS_PER_MESSAGE)
        repeats = (words[first] == words[last]) & (times[first] - times[last] <= late_after)
        starts[1:] &= ~repeats
    return m if starts.all() else int(np.argmin(starts))


def crc16_rows(messages: Array, sizes: Array) -> Array:
    """CRC-16/MODBUS of each row of ``messages`` over its first ``sizes`` bytes."""
    crc = np.full(messages.shape[0], 0xFFFF, np.int64)
    for size in distinct(sizes).tolist():
        rows = np.flatnonzero(sizes == size)
        crc[rows] = _crc16(messages[rows], size)
    return crc


def _crc16(messages: Array, size: int) -> Array:
    """CRC-16/MODBUS of the first ``size`` bytes of each row, two bytes a step: the
    register is 16 bits wide, so two bytes at once are one look-up of their XOR."""
    crc = np.full(messages.shape[0], 0xFFFF, np.int64)
    table = _crc_pairs()
    for column in range(0, size - 1, 2):
        crc = table[crc ^ messages[:, column] ^ (messages[:, column + 1] << 8)]
    if size % 2:
        crc = (crc >> 8) ^ _CRC[(crc ^ messages[:, size - 1]) & 0xFF]
    return crc


@functools.cache
def _crc_pairs() -> Array:
    """The CRC register after two bytes, by the register XOR those bytes."""
    value = np.arange(1 << 16, dtype=np.int64)
    low = (value >> 8) ^ _CRC[value & 0xFF]
    return (low >> 8) ^ _CRC[low & 0xFF]


def clean_messages(
    times: Array, data: Array, lengths: Array, late_after: float = LATE_AFTER_S
) -> Array:
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
