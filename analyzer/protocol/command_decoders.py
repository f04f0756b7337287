"""One generated decoder per row of the command table, for the usual 8 data bytes."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from operator import attrgetter
from typing import Any

from analyzer.protocol.command_table import BY_CODE, CommandRow
from analyzer.protocol.compiled import Code, layout_struct
from analyzer.protocol.fields import Field
from analyzer.protocol.ids import COMPONENT_NAMES

CAN_DATA_SIZE = 8
CommandDecoder = Callable[[bytes], tuple[dict[str, Any], list[str]]]


def unused_warning(name: str, data: bytes, unused: Sequence[int]) -> str | None:
    """The warning about bytes at ``unused`` offsets that are not zero (None if all are)."""
    listed = ", ".join(f"DATA{i - 1}=0x{data[i]:02X}" for i in unused if data[i] != 0)
    if not listed:
        return None
    return f"bytes not used by {name} are not zero: {listed}"


def _decoder(row: CommandRow, fields: Sequence[Field], variant: int | None) -> CommandDecoder:
    """Data (8 bytes) -> (values, warnings) of ``row`` decoded with ``fields`` in this order
    (the selector first, if any); ``variant`` is None when the selector's value has no
    layout (the general path says so right after the selector's own values)."""
    code = Code()
    constants = {
        "s_id": row.s_id,
        "cmd": row.cmd,
        "name": row.name,
        "component": COMPONENT_NAMES[row.s_id],
    }
    code.items += [f"{key!r}: {value!r}" for key, value in constants.items()]
    code.items.append("'raw': data.hex(' ').upper()")
    code.lines.append("    warnings = []")
    names = code.unpack(fields, CAN_DATA_SIZE)
    for position, (f, r) in enumerate(zip(fields, names, strict=True)):
        code.field(f, r)
        if position == 0 and row.selector is not None and variant is None:
            message = f"{f.name}: no layout for value "
            code.lines.append(f"    warnings.append({message!r} + str({r}))")
    used = {0, 1}.union(*(range(f.offset, f.end) for f in fields))
    unused = [i for i in range(CAN_DATA_SIZE) if i not in used]
    if unused:
        report = code.constant(unused_warning)
        name, where = code.constant(row.name), code.constant(tuple(unused))
        code.lines.append(f"    if {' or '.join(f'data[{i}]' for i in unused)}:")
        code.lines.append(f"        warnings.append({report}({name}, data, {where}))")
    decode: CommandDecoder = code.define(
        "decode(data)", [*code.lines, *code.filled(len(constants)), "    return fields, warnings"]
    )
    return decode


def command_fits(row: CommandRow) -> bool:
    """Whether ``row`` has a generated decoder: a one-byte selector, if any, and in every
    layout fields that fit in the 8 data bytes without overlapping."""
    if row.selector is None:
        return _fits(row.params)
    base = (row.selector, *row.params)
    variants = row.variants.values()
    return row.selector.kind == "u8" and _fits(base) and all(_fits((*base, *v)) for v in variants)


def _fits(fields: Sequence[Field]) -> bool:
    whole = layout_struct(sorted(fields, key=_OFFSET))
    return whole is not None and whole.size <= CAN_DATA_SIZE


_OFFSET = attrgetter("offset")


def compile_command(row: CommandRow) -> CommandDecoder | None:
    """The decoder of ``row`` for 8 data bytes; None for a layout this cannot generate."""
    if not command_fits(row):
        return None
    if row.selector is None:
        return _decoder(row, row.params, None)
    selector = row.selector
    other = _decoder(row, (selector, *row.params), None)
    by_value = [other] * 256
    for raw, variant in row.variants.items():
        by_value[raw] = _decoder(row, (selector, *row.params, *variant), raw)
    code = Code()
    table = code.constant(tuple(by_value))
    dispatch: CommandDecoder = code.define(
        "decode(data)", [f"    return {table}[data[{selector.offset}]](data)"]
    )
    return dispatch


# Decoders by ``S_ID << 8 | CMD`` (the first two data bytes), for exactly 8 data bytes.
# Made on first use by ``decoder_for``: a log holds a few kinds of command, and generating
# the decoder of every row would cost each start-up more than most logs gain from them.
COMMAND_DECODERS: dict[int, CommandDecoder] = {}


def decoder_for(key: int) -> CommandDecoder | None:
    """The decoder of the command ``S_ID << 8 | CMD`` (made now if need be); None for a
    command the table does not have or that has no generated decoder."""
    decoder = COMMAND_DECODERS.get(key)
    if decoder is None:
        row = BY_CODE.get((key >> 8, key & 0xFF))
        decoder = None if row is None else compile_command(row)
        if decoder is not None:
            COMMAND_DECODERS[key] = decoder
    return decoder
