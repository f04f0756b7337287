"""The protocol tables as a DBC file (cantools, SavvyCAN, CANdb++), with extended multiplexing."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, replace

from analyzer.export.literals import short_number
from analyzer.protocol.command_table import COMMANDS, CommandRow
from analyzer.protocol.fields import Field
from analyzer.protocol.ids import (
    COMPONENT_NAMES,
    CONTROL_ID,
    FEEDBACK_ID,
    TEXT_END_ID,
    TEXT_ID,
)
from analyzer.protocol.uav import STATUS_FRAMES

__all__ = [
    "CMD_SIGNALS",
    "COMMAND_MESSAGE",
    "S_ID_SIGNAL",
    "command_signal_name",
    "dbc_text",
    "frame_id",
]

GROUND_STATION = "ground_station"
GIMBAL = "gimbal"
FLIGHT_CONTROLLER = "flight_controller"

COMMAND_MESSAGE = "command"
S_ID_SIGNAL = "s_id"
# S_ID value -> the signal that holds CMD for that component (a nested multiplexer).
CMD_SIGNALS: dict[int, str] = {s_id: f"{name}_cmd" for s_id, name in COMPONENT_NAMES.items()}
_PREFIX = {s_id: "" if i == 0 else "ds_" for i, s_id in enumerate(COMPONENT_NAMES)}

_RAW_LIMITS = {
    "u8": (0, 0xFF),
    "s8": (-0x80, 0x7F),
    "u16": (0, 0xFFFF),
    "s16": (-0x8000, 0x7FFF),
    "u32": (0, 0xFFFFFFFF),
    "s32": (-0x80000000, 0x7FFFFFFF),
}


def frame_id(can_id: int) -> int:
    """The DBC form of an extended CAN ID (bit 31 set)."""
    return can_id | 0x80000000


def command_signal_name(row: CommandRow, f: Field) -> str:
    """The DBC signal of a command parameter: ``<command>_<field>``, ``ds_`` for 0x1F."""
    name = row.name if f.name == row.name else f"{row.name}_{f.name}"
    return _PREFIX[row.s_id] + name


@dataclass(frozen=True)
class _Signal:
    name: str
    start: int  # bit, Intel numbering
    length: int
    signed: bool
    factor: float
    minimum: float
    maximum: float
    unit: str
    comment: str
    labels: Mapping[int, str] | None = None
    mux_marker: str = ""  # "", "M", "m<n>" or "m<n>M"
    parent: tuple[str, int] | None = None  # (multiplexer, value) for SG_MUL_VAL_


@dataclass(frozen=True)
class _DbcMessage:
    can_id: int
    name: str
    sender: str
    comment: str
    signals: tuple[_Signal, ...]


def _text(value: str) -> str:
    return value.replace("\\", "/").replace('"', "'")


def _field_signal(f: Field, name: str, parent: tuple[str, int] | None = None) -> _Signal:
    lo_raw, hi_raw = _RAW_LIMITS[f.kind]
    labels: dict[int, str] | None = None
    notes: list[str] = []
    if f.labels is not None:
        labels = dict(f.labels)
        if f.other_label is not None:
            if 0 not in labels:
                labels[0] = f.other_label
            notes.append(f"any value not listed: {f.other_label}")
        else:
            lo_raw, hi_raw = min(labels), max(labels)
        labels = dict(sorted(labels.items()))
    else:
        lo_raw = f.minimum if f.minimum is not None else lo_raw
        hi_raw = f.maximum if f.maximum is not None else hi_raw
    if f.expected is not None:
        scaled = short_number(f.scale(f.expected))
        notes.append(f"the document prescribes raw {f.expected} ({scaled})")
    if f.soft_maximum is not None:
        notes.append(f"above {short_number(f.scale(f.soft_maximum))}: {f.soft_note}")
    comment = f.description + "".join(f"; {n}" for n in notes)
    marker = ""
    if parent is not None:
        marker = f"m{parent[1]}"
    return _Signal(
        name=name,
        start=f.offset * 8,
        length=f.size * 8,
        signed=f.kind.startswith("s"),
        factor=f.mul / f.div,
        minimum=f.scale(lo_raw),
        maximum=f.scale(hi_raw),
        unit=f.unit,
        comment=comment,
        labels=labels,
        mux_marker=marker,
        parent=parent,
    )


def _as_multiplexer(signal: _Signal, comment: str | None = None) -> _Signal:
    return replace(
        signal,
        mux_marker=signal.mux_marker + "M",
        comment=signal.comment if comment is None else comment,
    )


def _command_message() -> _DbcMessage:
    s_id_field = Field(S_ID_SIGNAL, 0, "u8", labels=COMPONENT_NAMES, description="S_ID")
    signals = [
        _as_multiplexer(
            _field_signal(s_id_field, S_ID_SIGNAL),
            "component: 0x0F gimbal / optical camera, 0x1F dual-sensor camera",
        )
    ]
    for s_id, component in COMPONENT_NAMES.items():
        rows = [r for r in COMMANDS if r.s_id == s_id]
        cmd_name = CMD_SIGNALS[s_id]
        cmd = Field(cmd_name, 1, "u8", labels={r.cmd: r.name for r in rows}, description="CMD")
        signals.append(
            _as_multiplexer(
                _field_signal(cmd, cmd_name, (S_ID_SIGNAL, s_id)),
                f"CMD of the {component.replace('_', '-')} commands",
            )
        )
        for row in rows:
            where = (cmd_name, row.cmd)
            for f in row.params:
                signals.append(_field_signal(f, command_signal_name(row, f), where))
            if row.selector is None:
                continue
            selector = command_signal_name(row, row.selector)
            signals.append(_as_multiplexer(_field_signal(row.selector, selector, where)))
            for key, variant in row.variants.items():
                for f in variant:
                    signals.append(_field_signal(f, command_signal_name(row, f), (selector, key)))
    return _DbcMessage(
        CONTROL_ID,
        COMMAND_MESSAGE,
        GROUND_STATION,
        "Gimbal control (chapter 2.1). s_id selects the component, gimbal_cmd or "
        "dual_sensor_cmd the command; specified_angle_axis selects yaw / pitch / zoom and "
        "snapshot_mode the snapshot parameter. Bytes a command does not use should be zero.",
        tuple(signals),
    )


def _byte_signals(prefix: str, comment: str) -> tuple[_Signal, ...]:
    return tuple(
        _Signal(f"{prefix}_{i}", i * 8, 8, False, 1, 0, 255, "", comment) for i in range(8)
    )


def _messages() -> list[_DbcMessage]:
    messages = [_command_message()]
    messages.append(
        _DbcMessage(
            FEEDBACK_ID,
            "gimbal_feedback_segment",
            GIMBAL,
            "Gimbal feedback (chapter 2.2): each 32-byte message (attitude, length byte 0x0C, "
            "or laser ranging, 0x10) spans four consecutive frames of this ID, about every "
            "500 ms, with one CRC over the whole message. A DBC cannot describe it: decode "
            "these frames with gimbal-analyzer (gimbal-analyzer decode FILE).",
            _byte_signals("segment_byte", "one byte of a 32-byte feedback message segment"),
        )
    )
    for status in STATUS_FRAMES.values():
        signals = tuple(_field_signal(f, f.name) for f in status.layout.fields)
        messages.append(
            _DbcMessage(
                status.can_id,
                f"uav_{status.name}",
                FLIGHT_CONTROLLER,
                f"{status.description} (chapter 2.3)",
                signals,
            )
        )
    text_comment = "ASCII character of a UAV text message (0 = padding)"
    messages.append(
        _DbcMessage(
            TEXT_ID,
            "uav_text",
            FLIGHT_CONTROLLER,
            "UAV text message, start and middle frames (chapter 2.3.4): 8 ASCII bytes per "
            "frame; the message continues until a uav_text_end frame. gimbal-analyzer joins "
            "the frames into one text.",
            _byte_signals("char", text_comment),
        )
    )
    messages.append(
        _DbcMessage(
            TEXT_END_ID,
            "uav_text_end",
            FLIGHT_CONTROLLER,
            "UAV text message, end frame (chapter 2.3.4): the last 8 ASCII bytes.",
            _byte_signals("char", text_comment),
        )
    )
    return messages


def _signal_line(s: _Signal, receiver: str) -> str:
    mux = f" {s.mux_marker}" if s.mux_marker else ""
    sign = "-" if s.signed else "+"
    return (
        f" SG_ {s.name}{mux} : {s.start}|{s.length}@1{sign} ({short_number(s.factor)},0) "
        f'[{short_number(s.minimum)}|{short_number(s.maximum)}] "{s.unit}" {receiver}'
    )


def _lines(messages: Iterable[_DbcMessage]) -> list[str]:
    messages = list(messages)
    out = [
        'VERSION ""',
        "",
        "NS_ :",
        "\tCM_",
        "\tVAL_",
        "\tSG_MUL_VAL_",
        "",
        "BS_:",
        "",
        f"BU_: {GROUND_STATION} {GIMBAL} {FLIGHT_CONTROLLER}",
        "",
    ]
    for m in messages:
        receiver = GROUND_STATION if m.sender == GIMBAL else GIMBAL
        out.append(f"BO_ {frame_id(m.can_id)} {m.name}: 8 {m.sender}")
        out.extend(_signal_line(s, receiver) for s in m.signals)
        out.append("")
    out.append('CM_ "Gimbal CAN protocol, generated by gimbal-analyzer export dbc.";')
    for m in messages:
        out.append(f'CM_ BO_ {frame_id(m.can_id)} "{_text(m.comment)}";')
        for s in m.signals:
            if s.comment:
                out.append(f'CM_ SG_ {frame_id(m.can_id)} {s.name} "{_text(s.comment)}";')
    for m in messages:
        for s in m.signals:
            if s.labels:
                pairs = " ".join(f'{k} "{_text(v)}"' for k, v in s.labels.items())
                out.append(f"VAL_ {frame_id(m.can_id)} {s.name} {pairs} ;")
    for m in messages:
        for s in m.signals:
            if s.parent is not None:
                mux, value = s.parent
                out.append(f"SG_MUL_VAL_ {frame_id(m.can_id)} {s.name} {mux} {value}-{value};")
    return out


def dbc_text() -> str:
    """The whole DBC file."""
    return "\n".join(_lines(_messages())) + "\n"
