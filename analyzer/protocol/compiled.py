"""Decoders generated as straight-line Python for fixed layouts: one struct.Struct each."""

from __future__ import annotations

import ast
import struct
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from analyzer.protocol.fields import Field

LayoutDecoder = Callable[[bytes, list[str]], dict[str, Any]]
FrameDecoder = Callable[[bytes], tuple[dict[str, Any], list[str]]]


def layout_struct(fields: Sequence[Field]) -> struct.Struct | None:
    """One little-endian struct.Struct reading every field (in the given order), skipping the
    bytes between them; None when fields overlap or are not in offset order."""
    fmt = "<"
    position = 0
    for f in fields:
        if f.offset < position:
            return None
        fmt += "x" * (f.offset - position) + f.struct_code
        position = f.offset + f.size
    return struct.Struct(fmt)


class Code:
    """Lines of a generated function, the names they use, and the values of the result.

    Raw numbers are read into ``r0``, ``r1``, ... (one per field, by ``unpack``); each
    field adds the lines that check it (appending to ``warnings`` in field order, as
    decoding field by field does) and the items of the result dict it fills.
    """

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.items: list[str] = []
        self.env: dict[str, Any] = {}
        self.raws = 0

    def unpack(self, fields: Sequence[Field], size: int | None = None) -> list[str]:
        """Read ``fields`` (any order, not overlapping) with one struct; their raw names.

        ``size``: bytes the data is known to have, to check that the fields fit."""
        order = sorted(range(len(fields)), key=lambda i: fields[i].offset)
        whole = layout_struct([fields[i] for i in order])
        if whole is None or (size is not None and whole.size > size):
            raise ValueError("fields overlap or do not fit")
        names = [f"r{self.raws + i}" for i in range(len(fields))]
        self.raws += len(fields)
        if fields:
            unpack = self.constant(whole.unpack_from)
            self.lines.append(f"    {', '.join(names[i] for i in order)}, = {unpack}(data)")
        return names

    def constant(self, value: object) -> str:
        """A name in the generated code for ``value``."""
        name = f"K{len(self.env)}"
        self.env[name] = value
        return name

    def field(self, f: Field, r: str) -> None:
        """The checks and result items of field ``f`` whose raw number is in ``r``."""
        fv = self.constant(f)
        if f.labels is not None:
            table = f.label_table()
            if isinstance(table, tuple):
                lookup = f"{self.constant(table)}[{r}]"
            else:
                lookup = f"{self.constant(table)}.get({r})"
            label = f"l{r}"
            self.lines.append(f"    {label} = {lookup}")
            self.lines.append(f"    if {label} is None:")
            self.lines.append(f"        {label} = {fv}.label_of({r}, warnings)")
            self.items += [f"{f.name!r}: {label}", f"{f.code_name!r}: {r}"]
            return
        if f.boolean:
            self.lines.append(f"    if {r} != 0 and {r} != 1:")
            self.lines.append(f"        {fv}.flag_of({r}, warnings)")
            self.items.append(f"{f.name!r}: {r} != 0")
            return
        if f.div == 1:
            value = r if f.mul == 1 else f"{r} * {f.mul}"
        else:
            value = f"{r} / {f.div}" if f.mul == 1 else f"{r} * {f.mul} / {f.div}"
        self.items.append(f"{f.name!r}: {value}")
        tests = []
        if f.expected is not None:
            tests.append(f"{r} != {f.expected}")
        if f.minimum is not None:
            tests.append(f"{r} < {f.minimum}")
        for limit in (f.maximum, f.soft_maximum):
            if limit is not None:
                tests.append(f"{r} > {limit}")
        if tests:
            self.lines.append(f"    if {' or '.join(tests)}:")
            self.lines.append(f"        {fv}.check({r}, warnings)")

    def fields(self, fields: Sequence[Field], size: int | None = None) -> None:
        for f, r in zip(fields, self.unpack(fields, size), strict=True):
            self.field(f, r)

    def result(self) -> str:
        return "{" + ", ".join(self.items) + "}"

    def filled(self, constants: int) -> list[str]:
        """Lines that make the result as ``fields``, the first ``constants`` items being
        literals: a copy of a dict that holds them and every other key in the order of
        the items (as the literal would), then the other values stored in order. Copying
        beats the literal when several values are constants."""
        pairs = [item.split(": ", 1) for item in self.items]
        template: dict[object, object] = {ast.literal_eval(key): None for key, _ in pairs}
        for key, value in pairs[:constants]:
            template[ast.literal_eval(key)] = ast.literal_eval(value)
        lines = [f"    fields = {self.constant(template)}.copy()"]
        lines += [f"    fields[{key}] = {value}" for key, value in pairs[constants:]]
        return lines

    def define(self, head: str, lines: list[str]) -> Any:
        """Compile ``def head:`` with ``lines`` as its body; returns the function."""
        source = "\n".join([f"def {head}:", *lines])
        namespace = dict(self.env)
        exec(compile(source, f"<decoder {head}>", "exec"), namespace)
        return namespace[head.split("(")[0]]


def compile_decoder(fields: Sequence[Field]) -> LayoutDecoder | None:
    """A function made for ``fields``: (data, warnings) -> values, exactly what decoding
    field by field gives; None when the fields overlap or are not in offset order."""
    if layout_struct(fields) is None:
        return None
    code = Code()
    code.fields(fields)
    decode: LayoutDecoder = code.define(
        "decode(data, warnings)", [*code.lines, f"    return {code.result()}"]
    )
    return decode


def compile_frame_decoder(
    fields: Sequence[Field],
    zero_from: int,
    size: int,
    on_nonzero: Callable[[bytes, list[str]], None],
) -> FrameDecoder:
    """Like ``compile_decoder``, for a whole frame of ``size`` bytes in one call: data ->
    (values, warnings); bytes from ``zero_from`` on that are not zero go to
    ``on_nonzero``."""
    code = Code()
    code.lines.append("    warnings = []")
    code.fields(fields, size)
    if zero_from < size:
        zeros, report = code.constant(bytes(size - zero_from)), code.constant(on_nonzero)
        code.lines += [
            f"    if data[{zero_from}:] != {zeros}:",
            f"        {report}(data, warnings)",
        ]
    decode: FrameDecoder = code.define(
        "decode(data)", [*code.lines, f"    return {code.result()}, warnings"]
    )
    return decode
