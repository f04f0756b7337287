"""Decode and encode the 8 CAN data bytes of gimbal commands, driven by the command table."""

from __future__ import annotations

from typing import Any

from analyzer.protocol.command_decoders import CAN_DATA_SIZE, decoder_for, unused_warning
from analyzer.protocol.command_table import BY_CODE, BY_NAME, COMMANDS, CommandRow
from analyzer.protocol.fields import EncodeError, Field, pad
from analyzer.protocol.ids import COMPONENT_NAMES
from analyzer.protocol.types import hexstr

__all__ = ["COMMANDS", "EncodeError", "decode_command", "encode_command", "find_command"]


def decode_command(data: bytes) -> tuple[dict[str, Any], list[str]]:
    """CAN data of a control frame -> (fields, warnings). Never raises.

    Returns a new dict and list on every call (callers add fields of their own). The usual
    frame (8 bytes, a command of the table) goes through that command's generated decoder,
    any other through ``decode_command_fields``, field by field, with the same result."""
    if len(data) == CAN_DATA_SIZE:
        decode = decoder_for(data[0] << 8 | data[1])
        if decode is not None:
            return decode(data)
    return decode_command_fields(data)


def decode_command_fields(data: bytes) -> tuple[dict[str, Any], list[str]]:
    """``decode_command`` the long way: any data, field by field as the table lists them."""
    warnings: list[str] = []
    raw = bytes(data)
    data = pad(raw, CAN_DATA_SIZE, "command frame", warnings)
    if len(raw) > CAN_DATA_SIZE:
        warnings.append(f"command frame: {len(raw)} data bytes, expected 8; extra bytes ignored")
        data = raw[:CAN_DATA_SIZE]
    s_id, cmd = data[0], data[1]
    out: dict[str, Any] = {"s_id": s_id, "cmd": cmd}
    row = BY_CODE.get((s_id, cmd))
    if row is None:
        out["name"] = "unknown"
        out["component"] = COMPONENT_NAMES.get(s_id, "unknown")
        out["raw"] = hexstr(raw)
        if s_id not in COMPONENT_NAMES:
            warnings.append(f"unknown component S_ID 0x{s_id:02X} (expected 0x0F or 0x1F)")
        else:
            warnings.append(f"unknown command CMD 0x{cmd:02X} for S_ID 0x{s_id:02X}")
        return out, warnings
    out["name"] = row.name
    out["component"] = COMPONENT_NAMES[s_id]
    out["raw"] = hexstr(raw)
    used: set[int] = {0, 1}
    fields: list[Field] = list(row.params)
    if row.selector is not None:
        selector = row.selector
        selector.decode_into(data, out, warnings)
        used.update(range(selector.offset, selector.end))
        variant = row.variants.get(selector.read_raw(data))
        if variant is None:
            warnings.append(f"{selector.name}: no layout for value {selector.read_raw(data)}")
        else:
            fields.extend(variant)
    for f in fields:
        f.decode_into(data, out, warnings)
        used.update(range(f.offset, f.end))
    unused = unused_warning(row.name, data, [i for i in range(CAN_DATA_SIZE) if i not in used])
    if unused is not None:
        warnings.append(unused)
    return out, warnings


def find_command(name: str, s_id: int | str | None = None) -> CommandRow:
    """The table row for a command name; ``s_id`` (number or component name) picks one."""
    rows = BY_NAME.get(name)
    if not rows:
        raise EncodeError(f"unknown command {name!r}; valid: {', '.join(BY_NAME)}")
    component = s_id if isinstance(s_id, str) else None
    if component is not None:
        wanted = [k for k, v in COMPONENT_NAMES.items() if v == component]
        if not wanted:
            raise EncodeError(
                f"unknown component {component!r}; valid: {', '.join(COMPONENT_NAMES.values())}"
            )
        s_id = wanted[0]
    if s_id is None:
        return rows[0]
    for row in rows:
        if row.s_id == s_id:
            return row
    if component is not None:
        valid = ", ".join(f"{COMPONENT_NAMES[r.s_id]} (S_ID 0x{r.s_id:02X})" for r in rows)
        raise EncodeError(
            f"{name} does not exist for component {component} (S_ID 0x{s_id:02X}); valid: {valid}"
        )
    valid = ", ".join(f"0x{r.s_id:02X}" for r in rows)
    raise EncodeError(f"{name} does not exist for S_ID 0x{s_id:02X}; valid: {valid}")


def encode_command(
    name: str,
    *,
    s_id: int | str | None = None,
    check_range: bool = True,
    require_all: bool = False,
    **params: Any,
) -> bytes:
    """Command name and physical values -> the 8 CAN data bytes.

    Raises EncodeError (a ValueError) naming the valid values or range.
    ``check_range=False`` lets out-of-range values through (for fault injection).
    A number left out is 0 unless ``require_all`` (the Python API's ``encode``): then
    every parameter without a default must be given.
    """
    params = dict(params)
    component = params.pop("component", None)
    row = find_command(name, s_id if s_id is not None else component)
    buffer = bytearray(CAN_DATA_SIZE)
    buffer[0], buffer[1] = row.s_id, row.cmd
    fields: list[Field] = list(row.params)
    choice_label = ""
    if row.selector is not None:
        selector = row.selector
        choice = params.pop(selector.name, None)
        if choice is None:
            choice = _infer_variant(row, params)
        raw = selector.to_raw(choice, check_range=check_range)
        choice_label = (selector.labels or {}).get(raw, str(raw))
        selector.write(buffer, raw, check_range=check_range)
        fields.extend(row.variants.get(raw, ()))
    known = {f.name for f in fields}
    unknown = sorted(set(params) - known)
    if unknown and row.selector is not None:
        variant_names = [f.name for variant in row.variants.values() for f in variant]
        misplaced = sorted(set(unknown) & set(variant_names))
        if misplaced:
            takes = ", ".join(f.name for f in fields if f.name in variant_names) or "no value"
            raise EncodeError(
                f"{name}: {row.selector.name}={choice_label} takes {takes}, "
                f"not {', '.join(misplaced)} (give only one of {', '.join(variant_names)})"
            )
    if unknown:
        valid = ", ".join(sorted(f.name for f in row.all_fields())) or "none"
        raise EncodeError(f"{name}: unknown parameter(s) {', '.join(unknown)}; valid: {valid}")
    for f in fields:
        if f.name in params:
            value = params[f.name]
        elif f.default is not None:
            value = f.default
        elif f.labels is not None or row.selector is not None or require_all:
            raise EncodeError(f"{name}: missing parameter {f.name} ({f.accepts()})")
        else:
            value = 0
        f.write(buffer, value, check_range=check_range)
    return bytes(buffer)


def _infer_variant(row: CommandRow, params: dict[str, Any]) -> int:
    assert row.selector is not None
    for raw, variant in row.variants.items():
        if variant and all(f.name in params for f in variant):
            return raw
    options = [f.name for variant in row.variants.values() for f in variant]
    raise EncodeError(f"{row.name}: give {row.selector.name} or one of {', '.join(options)}")
