"""Fixed layouts read from arrays of frames: every command, the UAV status frames, the feedback.

Made from the same tables as the generated scalar decoders (``command_decoders``,
``uav``, ``feedback``): for each command (each selector value of a command with
variants), each status frame and each feedback message, the fields in the order the
scalar decoder fills them. ``clean`` tells, for an (n, width) array of frames or
messages, which rows decode without a single warning (every label known, every flag 0
or 1, every number in range, unused and reserved bytes zero, fixed bytes as the
document prescribes) and ``values`` gives, for those rows, each field's values as
Python lists: exactly the numbers the scalar decoder makes (a scaled value is the same
integer product and the same correctly rounded division). Rows with a warning are left
to the scalar decoder, which says what is wrong.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from analyzer.protocol.command_decoders import CAN_DATA_SIZE, command_fits
from analyzer.protocol.command_table import BY_CODE, CommandRow
from analyzer.protocol.feedback import (
    ATTITUDE,
    FEEDBACK_ID_BYTES,
    LAYOUTS,
    MOTOR_YAW_LIMIT,
    WIDE_MOTOR_YAW_TYPES,
)
from analyzer.protocol.fields import Field
from analyzer.protocol.ids import COMPONENT_NAMES, FEEDBACK_MESSAGE_SIZE
from analyzer.protocol.types import TOPIC_COMMAND
from analyzer.protocol.uav import STATUS_FRAMES, USED_BYTES

Array = npt.NDArray[Any]

_DTYPES = {"u8": "<u1", "s8": "<i1", "u16": "<u2", "s16": "<i2", "u32": "<u4", "s32": "<i4"}
_HEX3 = np.frombuffer(b"".join(b"%02X " % b for b in range(256)), np.uint8).reshape(256, 3)


@dataclass(frozen=True)
class VectorLayout:
    """One layout of a frame's data bytes or of a feedback message: its topic, its
    result's keys in order, their constant values, the fields read, the bytes that must
    be zero, bytes the document fixes (offset, value) and a rule across fields (the rows
    it gives no warning)."""

    topic: str
    keys: tuple[str, ...]
    constants: dict[str, Any]
    fields: tuple[Field, ...]
    zero_bytes: tuple[int, ...]
    name: str | None = None  # the command's name (commands only)
    fixed: tuple[tuple[int, bytes], ...] = ()
    rule: Callable[[Array], Array] | None = None

    def clean(self, data: Array) -> Array:
        """Which rows of ``data`` decode without a warning."""
        ok = np.ones(data.shape[0], bool)
        for f in self.fields:
            ok &= _field_clean(f, _raw(data, f))
        if self.zero_bytes:
            ok &= ~data[:, list(self.zero_bytes)].any(axis=1)
        for offset, value in self.fixed:
            expected = np.frombuffer(value, np.uint8)
            ok &= (data[:, offset : offset + len(value)] == expected).all(axis=1)
        if self.rule is not None:
            ok &= self.rule(data)
        return ok

    def values(self, data: Array) -> dict[str, list[Any]]:
        """The values of every key that is no constant, for rows that are clean."""
        out: dict[str, list[Any]] = {"raw": hex_rows(data)}
        for f in self.fields:
            raw = _raw(data, f)
            if f.labels is not None:
                out[f.name] = _labels(f)[raw].tolist()
                out[f.code_name] = raw.tolist()
            elif f.boolean:
                out[f.name] = (raw != 0).tolist()
            elif f.div == 1:
                out[f.name] = (raw * f.mul if f.mul != 1 else raw).tolist()
            else:
                scaled = raw * f.mul if f.mul != 1 else raw
                out[f.name] = (scaled.astype(np.float64) / f.div).tolist()
        return out


def hex_rows(data: Array) -> list[str]:
    """Each row as upper-case hex pairs separated by spaces (``hexstr``)."""
    n, size = data.shape
    if not size:
        return [""] * n
    width = 3 * size
    text = _HEX3[data].reshape(n, width)[:, : width - 1].tobytes().decode("ascii")
    step = width - 1
    return [text[i : i + step] for i in range(0, n * step, step)]


def _raw(data: Array, f: Field) -> Array:
    part = np.ascontiguousarray(data[:, f.offset : f.offset + f.size])
    return part.view(_DTYPES[f.kind]).ravel().astype(np.int64)


_LABELS: dict[int, tuple[Field, Array]] = {}  # by id(field), the field kept alive


def _labels(f: Field) -> Array:
    """Labels by raw number, for the raw numbers a clean row can hold."""
    known = _LABELS.get(id(f))
    if known is None or known[0] is not f:
        known = _LABELS[id(f)] = (f, _label_array(f))
    return known[1]


def _label_array(f: Field) -> Array:
    table = f.label_table()
    if isinstance(table, tuple):
        return np.array(table, dtype=object)
    size = max(table) + 1 if table else 1
    out = np.empty(size, dtype=object)
    for raw, label in table.items():
        out[raw] = label
    return out


def _field_clean(f: Field, raw: Array) -> Array:
    if f.labels is not None:
        if f.other_label is not None:
            return np.ones(raw.shape[0], bool)
        return np.isin(raw, np.fromiter(f.labels, np.int64))
    if f.boolean:
        return (raw == 0) | (raw == 1)
    ok = np.ones(raw.shape[0], bool)
    if f.expected is not None:
        ok &= raw == f.expected
    if f.minimum is not None:
        ok &= raw >= f.minimum
    for limit in (f.maximum, f.soft_maximum):
        if limit is not None:
            ok &= raw <= limit
    return ok


def _items(fields: Sequence[Field]) -> list[str]:
    keys: list[str] = []
    for f in fields:
        keys.append(f.name)
        if f.labels is not None:
            keys.append(f.code_name)
    return keys


def _command_layout(row: CommandRow, fields: Sequence[Field]) -> VectorLayout:
    constants = {
        "s_id": row.s_id,
        "cmd": row.cmd,
        "name": row.name,
        "component": COMPONENT_NAMES[row.s_id],
    }
    used = {0, 1}.union(*(range(f.offset, f.end) for f in fields))
    unused = tuple(i for i in range(CAN_DATA_SIZE) if i not in used)
    keys = (*constants, "raw", *_items(fields))
    return VectorLayout(TOPIC_COMMAND, keys, constants, tuple(fields), unused, row.name)


@functools.cache
def command_layouts(key: int) -> dict[int | None, VectorLayout] | None:
    """The layouts of the command ``S_ID << 8 | CMD``: by selector value (None: the one
    layout of a command without selector); None for a command the table does not have,
    or whose layout has no generated decoder (the scalar decoder takes those)."""
    row = BY_CODE.get((key >> 8, key & 0xFF))
    if row is None or not command_fits(row):
        return None
    if row.selector is None:
        return {None: _command_layout(row, row.params)}
    selector = row.selector
    return {
        raw: _command_layout(row, (selector, *row.params, *variant))
        for raw, variant in row.variants.items()
    }


@functools.cache
def status_layout(can_id: int) -> VectorLayout:
    """The layout of a UAV status frame of 8 data bytes."""
    status = STATUS_FRAMES[can_id]
    fields = tuple(status.layout.fields)
    zeros = tuple(range(USED_BYTES[can_id], 8))
    return VectorLayout(status.topic, (*_items(fields), "raw"), {}, fields, zeros)


def _motor_yaw_in_range(data: Array) -> Array:
    """The attitude's rule across fields: a motor yaw beyond +-170 deg only on the models
    that turn further (``feedback.WIDE_MOTOR_YAW_TYPES``)."""
    names = [f.name for f in ATTITUDE.layout.fields]
    fields = ATTITUDE.layout.fields
    motor = _raw(data, fields[names.index("motor_yaw_deg")])
    kind = _raw(data, fields[names.index("gimbal_type")])
    wide = np.isin(kind, np.fromiter(WIDE_MOTOR_YAW_TYPES, np.int64))
    return (np.abs(motor) <= MOTOR_YAW_LIMIT) | wide


@functools.cache
def feedback_layout(length_byte: int) -> VectorLayout:
    """The layout of a whole feedback message (32 bytes) of this length byte."""
    layout = LAYOUTS[length_byte]
    fields = tuple(layout.layout.fields)
    zeros = (*range(3, 12), *range(layout.frame_size, FEEDBACK_MESSAGE_SIZE))
    rule = _motor_yaw_in_range if layout is ATTITUDE else None
    return VectorLayout(
        layout.topic,
        (*_items(fields), "raw"),
        {},
        fields,
        zeros,
        fixed=((12, FEEDBACK_ID_BYTES),),
        rule=rule,
    )
