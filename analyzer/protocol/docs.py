"""Markdown reference of every command and message, generated from the protocol tables."""

from __future__ import annotations

from analyzer.protocol.command_table import COMMANDS
from analyzer.protocol.feedback import LAYOUTS
from analyzer.protocol.fields import Field
from analyzer.protocol.ids import COMPONENT_NAMES, FEEDBACK_ID, TEXT_END_ID, TEXT_ID
from analyzer.protocol.types import TEXT_UNTERMINATED, TOPIC_UAV_TEXT
from analyzer.protocol.uav import STATUS_FRAMES

TEXT_NOTE = (
    "8 ASCII bytes per frame, NUL padding removed; a message that never ends is "
    f"reported as `{TEXT_UNTERMINATED}`."
)


def describe_field(f: Field, data_offset: int = 0) -> str:
    """One line about a field: bytes, type, unit, range, labels."""
    where = f"DATA{f.offset - 1}" if data_offset else f"byte {f.offset}"
    if f.size > 1:
        where += f"-{f.end - 2}" if data_offset else f"-{f.end - 1}"
    parts = [f"`{f.name}`", where, f.kind]
    if f.div != 1:
        parts.append(f"x{f.div}")
    if f.mul != 1:
        parts.append(f"/{f.mul}")
    if f.unit:
        parts.append(f.unit)
    lo, hi = f.value_limits()
    if lo is not None or hi is not None:
        parts.append(f"range [{f.format_value(lo)}, {f.format_value(hi)}]")
    if f.labels:
        labels = ", ".join(f"{k}={v}" for k, v in f.labels.items())
        if f.other_label:
            labels += f", other={f.other_label}"
        parts.append(f"values: {labels}")
    if f.expected is not None:
        parts.append(f"always {f.expected}")
    text = " ".join(parts)
    return f"{text}: {f.description}" if f.description else text


def command_reference() -> str:
    """The whole reference as a Markdown page (``gimbal-analyzer commands --markdown``)."""
    return "\n".join(
        [
            "# Protocol reference",
            "",
            "Generated from the protocol tables by `gimbal-analyzer commands --markdown`.",
            "",
            reference_body(),
        ]
    )


def reference_body() -> str:
    """Every command, feedback message and UAV status message, as Markdown sections
    (``##`` and ``###``); the manual's protocol page is made of it."""
    lines = [
        "A field with `values:` is decoded to its label, with the number on the wire in a "
        "companion field `<name>_code` (e.g. `palette: iron_red`, `palette_code: 2`); a number "
        "the table does not list gets the label `unknown_0x..` (e.g. `unknown_0x7f`) and a "
        "warning.",
        "",
        "## Commands (CAN ID 0x00000F01, TCP/UART frame type 0x0A)",
        "",
        "| S_ID | CMD | name | document name | parameters |",
        "|---|---|---|---|---|",
    ]
    for row in COMMANDS:
        params = [describe_field(f, 2) for f in row.params]
        if row.selector is not None:
            params.insert(0, describe_field(row.selector, 2))
            for key, variant in row.variants.items():
                label = (row.selector.labels or {}).get(key, str(key))
                inner = "; ".join(describe_field(f, 2) for f in variant) or "no parameter"
                params.append(f"when {row.selector.name}={label}: {inner}")
        cell = "<br>".join(params) if params else "none"
        lines.append(
            f"| 0x{row.s_id:02X} ({COMPONENT_NAMES[row.s_id]}) | 0x{row.cmd:02X} | `{row.name}` "
            f"| {row.title} | {cell} |"
        )
    lines += ["", f"## Gimbal feedback (CAN ID 0x{FEEDBACK_ID:08X}, 4 x 8-byte segments)", ""]
    for layout in LAYOUTS.values():
        lines.append(
            f"### {layout.name} (length byte 0x{layout.length_byte:02X}, topic `{layout.topic}`, "
            f"CRC at bytes {layout.crc_offset}-{layout.crc_offset + 1})"
        )
        lines.append("")
        lines += [f"- {describe_field(f)}" for f in layout.layout.fields]
        lines.append("")
    lines += ["## UAV status", ""]
    for status in STATUS_FRAMES.values():
        lines.append(f"### {status.name} (CAN ID 0x{status.can_id:08X}, topic `{status.topic}`)")
        lines.append("")
        lines += [f"- {describe_field(f)}" for f in status.layout.fields]
        lines.append("")
    lines += [
        f"### text (CAN IDs 0x{TEXT_ID:08X} start/middle, 0x{TEXT_END_ID:08X} end, "
        f"topic `{TOPIC_UAV_TEXT}`)",
        "",
        f"- {TEXT_NOTE}",
        "",
    ]
    return "\n".join(lines)
