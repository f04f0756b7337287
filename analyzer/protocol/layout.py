"""A frame's layout: its ordered fields, decoded by one precompiled struct and decoder."""

from __future__ import annotations

import functools
import struct
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from analyzer.protocol.compiled import LayoutDecoder, compile_decoder, layout_struct
from analyzer.protocol.fields import Field


@dataclass(frozen=True)
class Layout:
    """An ordered set of fields that together describe one frame or message."""

    fields: tuple[Field, ...]
    size: int
    extra: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        whole = layout_struct(self.fields)
        object.__setattr__(self, "_struct", whole)

    @functools.cached_property
    def _decode(self) -> LayoutDecoder | None:
        """The decoder made for this layout, on first use."""
        return compile_decoder(self.fields)

    def decode(self, data: bytes, warnings: list[str]) -> dict[str, Any]:
        whole: struct.Struct | None = self._struct  # type: ignore[attr-defined]
        decode = self._decode
        if whole is not None and decode is not None and len(data) >= whole.size:
            # One precompiled struct.Struct and a decoder made for this layout.
            return decode(data, warnings)
        out: dict[str, Any] = {}
        for f in self.fields:
            f.decode_into(data, out, warnings)
        return out

    def encode(self, values: Mapping[str, Any], *, check_range: bool = True) -> bytearray:
        buffer = bytearray(self.size)
        for f in self.fields:
            value = values.get(f.name, f.default if f.default is not None else 0)
            f.write(buffer, value, check_range=check_range)
        return buffer
