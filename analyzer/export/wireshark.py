"""The protocol tables as a Wireshark Lua dissector for the IDU's TCP link."""

from __future__ import annotations

from functools import cache
from importlib import resources

from analyzer.export.literals import lua_string
from analyzer.protocol.command_table import COMMANDS, CommandRow
from analyzer.protocol.feedback import (
    FEEDBACK_ID_BYTES,
    LAYOUTS,
    MOTOR_YAW_LIMIT,
    WIDE_MOTOR_YAW_TYPES,
    FeedbackLayout,
)
from analyzer.protocol.fields import Field
from analyzer.protocol.framing import FRAME_LENGTHS
from analyzer.protocol.ids import (
    COMPONENT_NAMES,
    CONTROL_ID,
    FEEDBACK_ID,
    FEEDBACK_MESSAGE_SIZE,
    FRAME_ATTITUDE,
    FRAME_CAN,
    FRAME_CONTROL,
    FRAME_RANGING,
    TCP_PORT,
    TEXT_END_ID,
    TEXT_ID,
)
from analyzer.protocol.uav import STATUS_FRAMES, USED_BYTES, StatusFrame

__all__ = ["command_abbr", "feedback_abbr", "lua_text", "status_abbr"]

PROTO = "gimbal"
FRAME_TYPE_NAMES = {
    FRAME_CONTROL: "control command",
    FRAME_CAN: "forwarded CAN frame",
    FRAME_ATTITUDE: "attitude feedback",
    FRAME_RANGING: "laser ranging feedback",
}


def _shape(f: Field) -> tuple[object, ...]:
    """What must agree for two commands to share one Wireshark field."""
    labels = tuple(sorted((f.labels or {}).items()))
    return (f.kind, f.div, f.mul, f.unit, labels, f.other_label, f.boolean)


@cache
def _command_abbrs() -> dict[tuple[int, int, str], str]:
    """gimbal.<command>.<field>, shared by both components when the field is the same."""
    out: dict[tuple[int, int, str], str] = {}
    shapes: dict[str, tuple[object, ...]] = {}
    for row in COMMANDS:
        for f in row.all_fields():
            abbr = f"{PROTO}.{row.name}.{f.name}"
            if shapes.setdefault(abbr, _shape(f)) != _shape(f):
                abbr = f"{PROTO}.{COMPONENT_NAMES[row.s_id]}.{row.name}.{f.name}"
            out[(row.s_id, row.cmd, f.name)] = abbr
    return out


def command_abbr(row: CommandRow, f: Field) -> str:
    """Display-filter name of a command parameter, e.g. ``gimbal.gimbal_control.pan_speed_dps``."""
    return _command_abbrs()[(row.s_id, row.cmd, f.name)]


def feedback_abbr(layout: FeedbackLayout, f: Field) -> str:
    return f"{PROTO}.{layout.name}.{f.name}"


def status_abbr(status: StatusFrame, f: Field) -> str:
    return f"{PROTO}.uav_{status.name}.{f.name}"


def _spec(abbr: str, f: Field) -> str:
    """A Lua table describing one field; the dissector body turns it into a ProtoField."""
    text = f.description + (f" [{f.unit}]" if f.unit else "")
    items = [
        f"abbr={lua_string(abbr)}",
        f"name={lua_string(f.name)}",
        f"desc={lua_string(text)}",
        f"off={f.offset}",
        f"size={f.size}",
        f"signed={'true' if f.kind.startswith('s') else 'false'}",
        f"div={f.div}",
        f"mul={f.mul}",
        f"decimals={f.decimals}",
        f"unit_suffix={lua_string(' ' + f.unit if f.unit else '')}",
    ]
    if f.labels is not None:
        pairs = ", ".join(f"[{k}]={lua_string(v)}" for k, v in sorted(f.labels.items()))
        items.append(f"labels={{{pairs}}}")
        if f.other_label is not None:
            items.append(f"other_label={lua_string(f.other_label)}")
    if f.boolean:
        items.append("boolean=true")
    if f.minimum is not None or f.maximum is not None:
        lo, hi = f.value_limits()
        items.append(f"min={f.minimum if f.minimum is not None else 'nil'}")
        items.append(f"max={f.maximum if f.maximum is not None else 'nil'}")
        items.append(f"min_text={lua_string(f.format_value(lo))}")
        items.append(f"max_text={lua_string(f.format_value(hi))}")
    if f.expected is not None:
        items.append(f"expected={f.expected}")
    if f.soft_maximum is not None:
        items.append(f"soft_max={f.soft_maximum}")
        items.append(f"soft_note={lua_string(f.soft_note)}")
    return "F{" + ", ".join(items) + "}"


def _table(pairs: dict[int, str], width: int) -> str:
    return "{" + ", ".join(f"[0x{k:0{width}X}]={lua_string(v)}" for k, v in pairs.items()) + "}"


def _generated() -> list[str]:
    can_names = {CONTROL_ID: "command", FEEDBACK_ID: "gimbal feedback segment"}
    can_names.update({cid: f"UAV {s.name}" for cid, s in STATUS_FRAMES.items()})
    can_names.update({TEXT_ID: "UAV text (start/middle)", TEXT_END_ID: "UAV text (end)"})
    lines = [
        "-- Wireshark dissector for the gimbal protocol on the IDU's TCP link (port 2000).",
        "-- Generated from the protocol tables by `gimbal-analyzer export wireshark`:",
        "-- do not edit; regenerate it instead.",
        "--",
        "-- Use: wireshark -X lua_script:gimbal.lua capture.pcap",
        "--   or copy it into the personal Lua plugins folder (Help > About > Folders).",
        "-- The port is a preference: Edit > Preferences > Protocols > GIMBAL.",
        "",
        f"local DEFAULT_PORT = {TCP_PORT}",
        f"local FRAME_CONTROL = 0x{FRAME_CONTROL:02X}",
        f"local FRAME_CAN = 0x{FRAME_CAN:02X}",
        f"local CONTROL_ID = 0x{CONTROL_ID:08X}",
        f"local TEXT_ID = 0x{TEXT_ID:08X}",
        f"local TEXT_END_ID = 0x{TEXT_END_ID:08X}",
        f"local FEEDBACK_SIZE = {FEEDBACK_MESSAGE_SIZE}",
        f"local MIN_FEEDBACK_FRAME = {min(layout.frame_size for layout in LAYOUTS.values())}",
        f"local FEEDBACK_ID_BYTES = {lua_string(FEEDBACK_ID_BYTES.hex(' ').upper())}",
        f"local MOTOR_YAW_LIMIT = {MOTOR_YAW_LIMIT}",
        "local WIDE_MOTOR_YAW_TYPES = {"
        + ", ".join(f"[{t}]=true" for t in sorted(WIDE_MOTOR_YAW_TYPES))
        + "}",
        "local FRAME_SIZES = "
        + "{"
        + ", ".join(f"[0x{k:02X}]={v}" for k, v in FRAME_LENGTHS.items())
        + "}",
        f"local FRAME_TYPE_NAMES = {_table(FRAME_TYPE_NAMES, 2)}",
        f"local CAN_ID_NAMES = {_table(can_names, 8)}",
        f"local COMPONENT_NAMES = {_table(COMPONENT_NAMES, 2)}",
        "",
        "local FIELD_SPECS = {}",
        "local function F(spec) FIELD_SPECS[#FIELD_SPECS + 1] = spec; return spec end",
        "",
        "local COMMANDS = {}",
    ]
    for row in COMMANDS:
        parts = [f"name={lua_string(row.name)}", f"title={lua_string(row.title)}"]
        params = ", ".join(_spec(command_abbr(row, f), f) for f in row.params)
        parts.append(f"params={{{params}}}")
        if row.selector is not None:
            parts.append(f"selector={_spec(command_abbr(row, row.selector), row.selector)}")
            variants = ", ".join(
                f"[{key}]={{" + ", ".join(_spec(command_abbr(row, f), f) for f in fields) + "}"
                for key, fields in row.variants.items()
            )
            parts.append(f"variants={{{variants}}}")
        lines.append(f"COMMANDS[0x{row.s_id:02X}{row.cmd:02X}] = {{" + ", ".join(parts) + "}")
    lines.append("local FEEDBACK = {}")
    for key, layout in LAYOUTS.items():
        specs = ", ".join(_spec(feedback_abbr(layout, f), f) for f in layout.layout.fields)
        lines.append(
            f"FEEDBACK[0x{key:02X}] = {{name={lua_string(layout.name)}, "
            f"size={layout.frame_size}, fields={{{specs}}}}}"
        )
    lines.append("local STATUS = {}")
    for can_id, status in STATUS_FRAMES.items():
        specs = ", ".join(_spec(status_abbr(status, f), f) for f in status.layout.fields)
        lines.append(
            f"STATUS[0x{can_id:08X}] = {{name={lua_string('uav_' + status.name)}, "
            f"used={USED_BYTES[can_id]}, fields={{{specs}}}}}"
        )
    lines.append("")
    return lines


def lua_text() -> str:
    """The whole dissector: generated tables, then the fixed body."""
    body = resources.files("analyzer.export").joinpath("dissector.lua").read_text("utf-8")
    return "\n".join(_generated()) + "\n" + body
