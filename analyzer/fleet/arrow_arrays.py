"""Python values into numpy buffers and Arrow arrays made from them, never through ``pa.array``.

When pandas is installed, pyarrow imports it the first time ``pa.array`` or ``pa.scalar``
is called (to tell pandas objects apart), and pandas costs ``table`` tens of MB and a
fifth of a second it has no use for. The functions here take the same Python values as
``pa.array(values, kind)`` for the types of the fleet tables (string, int64, float64,
bool, list of strings, timestamps) and refuse those it refuses, with ``Unfit``: a float
in an int64 column is truncated, an integer in a float64 column is taken when a double
holds it exactly, a bool is 1.0 in a float64 column but refused in an int64 one. None
is null.

``fixed``, ``texts`` and ``text_lists`` give a column's values as numpy arrays (what the
column builders keep); ``fixed_array``, ``text_array`` and ``list_array`` make Arrow
arrays of those; ``column`` does both.
"""

from __future__ import annotations

import operator
from itertools import chain, repeat
from typing import Any, NamedTuple

import numpy as np
import numpy.typing as npt
import pyarrow as pa

from analyzer.fleet.columns import TIME

STRING = pa.string()
INT = pa.int64()
FLOAT = pa.float64()
BOOL = pa.bool_()
STRINGS = pa.list_(pa.string())
FIXED_TYPES: dict[pa.DataType, type[np.generic]] = {
    INT: np.int64,
    FLOAT: np.float64,
    BOOL: np.bool_,
    TIME: np.int64,
}
_OFFSET_LIMIT = (1 << 31) - 1  # what 32-bit offsets reach (pyarrow makes chunks past it)
_EXACT = 1 << 53  # above it, not every integer is a double
_NUMBERS = (int, float, np.integer, np.floating)

Bools = npt.NDArray[np.bool_]
Lengths = npt.NDArray[np.signedinteger[Any]]


class Unfit(TypeError):
    """A value of a type the column cannot take (``pa.array`` raises on it too)."""


class Texts(NamedTuple):
    """Strings as numpy: each row's length in bytes (0 when null), the UTF-8 bytes of
    every row one after the other, which rows are not null (None: all)."""

    lengths: Lengths
    data: bytes | npt.NDArray[np.uint8]
    valid: Bools | None


class TextLists(NamedTuple):
    """Lists of strings: each row's number of items (0 when null), the items one after
    the other, which rows are not null (None: all)."""

    lengths: Lengths
    items: Texts
    valid: Bools | None


def column(values: list[Any], kind: pa.DataType) -> pa.Array:
    """``pa.array(values, kind)``: ``Unfit`` for a value of another type, OverflowError
    for an integer the column cannot hold."""
    n = len(values)
    if values.count(None) == n:
        return pa.nulls(n, kind)
    if kind == STRING:
        return text_array(texts(values))
    if kind == STRINGS:
        return list_array(text_lists(values))
    data, valid = fixed(values, kind)
    return fixed_array(kind, data, valid)


def _present(values: list[Any]) -> tuple[list[Any], Bools | None]:
    """The values that are not None, and which rows they are (None: all)."""
    if None not in values:
        return values, None
    n = len(values)
    valid = np.fromiter(map(operator.is_not, values, repeat(None)), np.bool_, n)
    return [v for v in values if v is not None], valid


def fixed(values: list[Any], kind: pa.DataType) -> tuple[npt.NDArray[Any], Bools | None]:
    """Numbers, bools or timestamps (as microseconds) as a numpy array of every row (0
    where null) and which rows are not null (None: all)."""
    present, valid = _present(values)
    data = _numbers(present, INT if kind == TIME else kind)
    if valid is None:
        return data, None
    full = np.zeros(len(valid), data.dtype)
    full[valid] = data
    return full, valid


def _numbers(values: list[Any], kind: pa.DataType) -> npt.NDArray[Any]:
    """The values (none None) as a numpy array of the column's type, with pyarrow's rules."""
    kinds = set(map(type, values))
    if kind == BOOL:
        if not all(k is bool or issubclass(k, np.bool_) for k in kinds):
            raise Unfit(f"expected booleans, got {_names(kinds)}")
        return np.array(values, np.bool_)
    if kind == INT:
        # pyarrow truncates floats and refuses bools (but takes numpy's)
        if bool in kinds or not all(issubclass(k, (*_NUMBERS, np.bool_)) for k in kinds):
            raise Unfit(f"expected integers, got {_names(kinds)}")
        try:
            return np.array(values, np.int64)
        except ValueError as exc:  # NaN (infinity and too large: OverflowError)
            raise Unfit(str(exc)) from None
    if kind == FLOAT:
        if not all(issubclass(k, _NUMBERS) for k in kinds):  # bool is an int: 1.0
            raise Unfit(f"expected numbers, got {_names(kinds)}")
        if any(issubclass(k, (int, np.integer)) for k in kinds):
            big = [v for v in values if isinstance(v, (int, np.integer)) and abs(v) > _EXACT]
            if big:
                raise OverflowError(f"integer value {big[0]} is beyond what a double holds exactly")
        return np.array(values, np.float64)
    raise Unfit(f"no conversion to {kind}")


def _names(kinds: set[type]) -> str:
    return ", ".join(sorted(k.__name__ for k in kinds))


def texts(values: list[Any]) -> Texts:
    """Strings (bytes decoded as UTF-8, as pyarrow does) as numpy; Unfit for others."""
    present, valid = _present(values)
    kinds = set(map(type, present))
    if not all(issubclass(k, str) for k in kinds):
        if not all(issubclass(k, (str, bytes)) for k in kinds):
            raise Unfit(f"expected strings, got {_names(kinds)}")
        try:
            present = [v.decode("utf-8") if isinstance(v, bytes) else v for v in present]
        except UnicodeDecodeError as exc:
            raise Unfit(f"not UTF-8: {exc}") from None
    joined = "".join(present)
    data = joined.encode("utf-8")
    if len(data) == len(joined):  # ASCII: a character is a byte
        lengths = np.fromiter(map(len, present), np.int64, len(present))
    else:
        lengths = np.fromiter((len(t.encode("utf-8")) for t in present), np.int64, len(present))
    return Texts(_spread(lengths, valid), data, valid)


def text_lists(values: list[Any]) -> TextLists:
    """Lists (or tuples) of strings as numpy; Unfit for others."""
    present, valid = _present(values)
    kinds = set(map(type, present))
    if not all(issubclass(k, (list, tuple)) for k in kinds):
        raise Unfit(f"expected lists, got {_names(kinds)}")
    lengths = np.fromiter(map(len, present), np.int64, len(present))
    items = list(chain.from_iterable(present))
    return TextLists(_spread(lengths, valid), texts(items), valid)


def _spread(lengths: Lengths, valid: Bools | None) -> Lengths:
    """The lengths of the rows that are not null, as every row's (0 where null)."""
    if valid is None:
        return lengths
    full = np.zeros(len(valid), np.int64)
    full[valid] = lengths
    return full


def fixed_array(kind: pa.DataType, data: npt.NDArray[Any], valid: Bools | None) -> pa.Array:
    """An array of ``kind`` over numpy ``data`` (one value a row) and ``valid``."""
    n = len(data)
    if kind == BOOL:
        data = np.packbits(data, bitorder="little")
    buffers = [_bitmap(valid), pa.py_buffer(data)]
    return pa.Array.from_buffers(kind, n, buffers, null_count=_nulls(valid))


def text_array(values: Texts) -> pa.Array:
    """A string array of ``values``."""
    offsets = _offsets(values.lengths, "more than 2 GiB of text in one column")
    buffers = [_bitmap(values.valid), offsets, pa.py_buffer(values.data)]
    return pa.Array.from_buffers(
        STRING, len(values.lengths), buffers, null_count=_nulls(values.valid)
    )


def list_array(values: TextLists) -> pa.Array:
    """A list-of-strings array of ``values``."""
    offsets = _offsets(values.lengths, "more than 2**31 strings in one column")
    return pa.Array.from_buffers(
        STRINGS,
        len(values.lengths),
        [_bitmap(values.valid), offsets],
        null_count=_nulls(values.valid),
        children=[text_array(values.items)],
    )


def _offsets(lengths: Lengths, too_many: str) -> pa.Buffer:
    if int(lengths.sum(dtype=np.int64)) > _OFFSET_LIMIT:
        raise OverflowError(too_many)
    offsets = np.zeros(len(lengths) + 1, np.int32)
    np.cumsum(lengths, out=offsets[1:], dtype=np.int32)
    return pa.py_buffer(offsets)


def _bitmap(valid: Bools | None) -> pa.Buffer | None:
    return None if valid is None else pa.py_buffer(np.packbits(valid, bitorder="little"))


def _nulls(valid: Bools | None) -> int:
    return 0 if valid is None else len(valid) - int(np.count_nonzero(valid))


def repeated(text: str, n: int) -> pa.Array:
    """``n`` times the same string."""
    data = text.encode("utf-8")
    return text_array(Texts(np.full(n, len(data), np.int64), data * n, None))
