"""Declarative fixed-position fields: how one value sits in a frame, and its codec."""

from __future__ import annotations

import math
import re
import struct
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

# kind -> (struct format, size, minimum raw, maximum raw)
_KINDS: dict[str, tuple[str, int, int, int]] = {
    "u8": ("<B", 1, 0, 0xFF),
    "s8": ("<b", 1, -0x80, 0x7F),
    "u16": ("<H", 2, 0, 0xFFFF),
    "s16": ("<h", 2, -0x8000, 0x7FFF),
    "u32": ("<I", 4, 0, 0xFFFFFFFF),
    "s32": ("<i", 4, -0x80000000, 0x7FFFFFFF),
}

_STRUCTS = {kind: struct.Struct(fmt) for kind, (fmt, _, _, _) in _KINDS.items()}


# A labelled field ``X`` holds the label (a string); ``X_code`` holds the raw number.
CODE_SUFFIX = "_code"
UNKNOWN_PREFIX = "unknown_0x"
# Characters escaped in label patterns (only these: the pattern is also an ECMA-262 regex).
_REGEX_SPECIAL = re.compile(r"[.^$*+?()\[\]{}|\\/]")


def label_pattern(fields: list[Field]) -> str:
    """Regular expression matching the labels of ``fields`` (and ``unknown_0x..``)."""
    names: dict[str, None] = {}
    width = 2
    for f in fields:
        names.update(dict.fromkeys((f.labels or {}).values()))
        if f.other_label:
            names[f.other_label] = None
        width = max(width, 2 * f.size)
    known = "|".join(_REGEX_SPECIAL.sub(r"\\\g<0>", n) for n in names)
    return f"^({known}|{UNKNOWN_PREFIX}[0-9a-f]{{{width}}})$"


def _unknown_code(label: str) -> int | None:
    """``unknown_0x7f`` -> 127; None for anything else."""
    if not label.startswith(UNKNOWN_PREFIX):
        return None
    digits = label[len(UNKNOWN_PREFIX) :]
    if not digits or any(c not in "0123456789abcdefABCDEF" for c in digits):
        return None
    return int(digits, 16)


class EncodeError(ValueError):
    """A value that cannot be encoded: unknown name, bad label or out of range."""


@dataclass(frozen=True)
class Field:
    """One value at a fixed byte offset of a frame.

    The physical value is ``raw * mul / div``; ``minimum``/``maximum`` are raw limits
    from the protocol document (out-of-range values are decoded and flagged).
    """

    name: str
    offset: int
    kind: str = "u8"
    div: int = 1
    mul: int = 1
    unit: str = ""
    minimum: int | None = None
    maximum: int | None = None
    labels: Mapping[int, str] | None = None
    other_label: str | None = None  # label for raw values that are not in ``labels``
    boolean: bool = False
    expected: int | None = None  # a fixed raw value the document prescribes
    default: Any = None  # value used by encode() when the caller leaves it out
    description: str = ""
    soft_maximum: int | None = None  # above this: valid only on some models (warn)
    soft_note: str = ""

    @property
    def code_name(self) -> str:
        """Name of the companion field that keeps the raw number of a labelled value."""
        return self.name + CODE_SUFFIX

    def unknown_label(self, raw: int) -> str:
        """Label of a raw value the table does not know: ``unknown_0x7f``."""
        return f"{UNKNOWN_PREFIX}{raw:0{2 * self.size}x}"

    def label_pattern(self) -> str:
        """Regular expression matching every label this field can decode to."""
        return label_pattern([self])

    @property
    def size(self) -> int:
        return _KINDS[self.kind][1]

    @property
    def struct_code(self) -> str:
        """The struct module's format character of this field's kind."""
        return _KINDS[self.kind][0][1:]

    @property
    def end(self) -> int:
        return self.offset + self.size

    @property
    def decimals(self) -> int:
        return 0 if self.div == 1 else math.ceil(math.log10(self.div))

    def raw_limits(self) -> tuple[int, int]:
        """Lowest and highest raw number to send: the document's range, else the kind's."""
        _, _, kind_lo, kind_hi = _KINDS[self.kind]
        lo = kind_lo if self.minimum is None else self.minimum
        hi = kind_hi if self.maximum is None else self.maximum
        return lo, hi

    def value_limits(self) -> tuple[float | None, float | None]:
        """Minimum and maximum in physical units."""
        lo = None if self.minimum is None else self.scale(self.minimum)
        hi = None if self.maximum is None else self.scale(self.maximum)
        return lo, hi

    def encodable_limits(self, *, check_range: bool = True) -> tuple[int, int]:
        """The lowest and highest raw number ``encode`` writes: the document's range (with
        ``check_range``), else what the field's bytes hold."""
        _, _, kind_lo, kind_hi = _KINDS[self.kind]
        lo = self.minimum if check_range and self.minimum is not None else kind_lo
        hi = self.maximum if check_range and self.maximum is not None else kind_hi
        return lo, hi

    def accepts(self) -> str:
        """What ``encode`` takes for this field, for messages: its labels or its range."""
        if self.labels is not None:
            labels = [*self.labels.values(), *([self.other_label] if self.other_label else [])]
            return f"one of {', '.join(labels)}"
        lo, hi = self.encodable_limits()
        unit = f" {self.unit}" if self.unit else ""
        low, high = self.format_value(self.scale(lo)), self.format_value(self.scale(hi))
        return f"range [{low}, {high}]{unit}"

    def scale(self, raw: int) -> float | int:
        if self.div == 1:
            return raw * self.mul
        return raw * self.mul / self.div

    # -- decoding ---------------------------------------------------------------------------

    def read_raw(self, data: bytes) -> int:
        raw: int = _STRUCTS[self.kind].unpack_from(data, self.offset)[0]
        return raw

    def decode_into(self, data: bytes, out: dict[str, Any], warnings: list[str]) -> None:
        """Decode this field of ``data`` into ``out``; doubts go to ``warnings``."""
        self.decode_raw(self.read_raw(data), out, warnings)

    def decode_raw(self, raw: int, out: dict[str, Any], warnings: list[str]) -> None:
        """Put the value of the raw number ``raw`` into ``out``; doubts go to ``warnings``."""
        if self.labels is not None:
            out[self.name] = self.label_of(raw, warnings)
            out[self.name + CODE_SUFFIX] = raw
            return
        if self.boolean:
            out[self.name] = self.flag_of(raw, warnings)
            return
        out[self.name] = self.scale(raw)
        self.check(raw, warnings)

    def label_of(self, raw: int, warnings: list[str]) -> str:
        """The label of a labelled field's raw number (``unknown_0x..`` with a warning)."""
        label = (self.labels or {}).get(raw, self.other_label)
        if label is None:
            warnings.append(f"{self.name}: unknown value {raw} (0x{raw:02X})")
            label = self.unknown_label(raw)
        return label

    def label_table(self) -> tuple[str | None, ...] | dict[int, str | None]:
        """Labels by raw number, None where ``label_of`` must be asked: a tuple indexed by
        the raw number for u8 fields, else a dict."""
        labels, other = self.labels or {}, self.other_label
        if self.kind == "u8":
            return tuple(labels.get(raw, other) for raw in range(256))
        return dict(labels)

    def flag_of(self, raw: int, warnings: list[str]) -> bool:
        """A flag's value; a warning when it is neither 0 nor 1."""
        if raw not in (0, 1):
            warnings.append(f"{self.name}: flag value {raw}, expected 0 or 1")
        return raw != 0

    def check(self, raw: int, warnings: list[str]) -> None:
        """Warn about a plain number that is not what the document prescribes or allows."""
        if self.expected is not None and raw != self.expected:
            warnings.append(
                f"{self.name}: raw value {raw}, the document prescribes {self.expected}"
            )
        lo, hi = self.minimum, self.maximum
        if (lo is not None and raw < lo) or (hi is not None and raw > hi):
            vlo, vhi = self.value_limits()
            unit = f" {self.unit}" if self.unit else ""
            warnings.append(
                f"{self.name}: {self.format_value(self.scale(raw))}{unit} out of range "
                f"[{self.format_value(vlo)}, {self.format_value(vhi)}]{unit}"
            )
        elif self.soft_maximum is not None and raw > self.soft_maximum:
            warnings.append(f"{self.name}: {self.format_value(self.scale(raw))} {self.soft_note}")

    def format_value(self, value: float | int | None) -> str:
        if value is None:
            return "-"
        if self.div == 1:
            return str(value)
        return f"{value:.{self.decimals}f}"

    # -- encoding ---------------------------------------------------------------------------

    def to_raw(self, value: Any, *, check_range: bool = True) -> int:
        """Physical value (or label) -> raw integer, with clear errors."""
        if self.labels is not None and isinstance(value, str):
            for raw, label in self.labels.items():
                if label == value:
                    return raw
            if self.other_label is not None and value == self.other_label:
                return 0
            code = _unknown_code(value)
            if code is None:
                valid = ", ".join(self.labels.values())
                raise EncodeError(f"{self.name}: unknown value {value!r}; valid: {valid}")
            value = code  # a decoded unknown value, checked below like a raw number
        if isinstance(value, bool):
            raw = int(value)
        elif isinstance(value, int) and self.labels is not None:
            raw = value
        else:
            try:
                number = float(value)
            except (TypeError, ValueError):
                raise EncodeError(f"{self.name}: {value!r} is not a number") from None
            if not math.isfinite(number):
                raise EncodeError(f"{self.name}: {value!r} is not a finite number")
            raw = round(number * self.div / self.mul)
        lo, hi = self.encodable_limits(check_range=check_range)
        unlabelled = self.labels is not None and raw not in self.labels
        if check_range and unlabelled and self.other_label is None:
            valid = ", ".join(f"{v} ({k})" for k, v in (self.labels or {}).items())
            raise EncodeError(f"{self.name}: unknown value {raw}; valid: {valid}")
        if not lo <= raw <= hi:
            vlo, vhi = (self.scale(lo), self.scale(hi))
            unit = f" {self.unit}" if self.unit else ""
            raise EncodeError(
                f"{self.name}: {value} out of range "
                f"[{self.format_value(vlo)}, {self.format_value(vhi)}]{unit}"
            )
        return raw

    def write(self, buffer: bytearray, value: Any, *, check_range: bool = True) -> None:
        _STRUCTS[self.kind].pack_into(
            buffer, self.offset, self.to_raw(value, check_range=check_range)
        )

    # -- documentation ----------------------------------------------------------------------

    def json_schema(self) -> dict[str, Any]:
        """JSON Schema of the decoded value(s) of this field."""
        schema: dict[str, Any] = {}
        text = self.description
        if self.unit:
            text = f"{text} [{self.unit}]" if text else f"[{self.unit}]"
        if self.labels is not None:
            values = ", ".join(f"{k} = {v}" for k, v in self.labels.items())
            if self.other_label:
                values += f", other = {self.other_label}"
            return {
                "type": "string",
                "pattern": self.label_pattern(),
                "description": f"{text} ({values}; '{UNKNOWN_PREFIX}..' for a value the "
                f"document does not list; the number is in {self.code_name})",
            }
        if self.boolean:
            return {"type": "boolean", "description": text}
        schema["type"] = "integer" if self.div == 1 else "number"
        lo, hi = self.value_limits()
        notes = []
        if lo is not None or hi is not None:
            notes.append(f"documented range [{self.format_value(lo)}, {self.format_value(hi)}]")
        if notes:
            text = f"{text}; {', '.join(notes)}" if text else ", ".join(notes)
        schema["description"] = text
        return schema


def pad(data: bytes, size: int, what: str, warnings: list[str]) -> bytes:
    """Zero-pad short data so fixed-offset fields can be read; say so in warnings."""
    if len(data) < size:
        warnings.append(f"{what}: {len(data)} data bytes, expected {size}; missing bytes read as 0")
        return bytes(data) + bytes(size - len(data))
    return bytes(data)
