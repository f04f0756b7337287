"""A column of a fleet table whose rows wait for their row group in numpy buffers that stay.

Each block's values are converted (``arrow_arrays``) and copied in; a row group is
taken out as an Arrow array over the buffers themselves, and the rows after it move
to the front at the next append (so the array is only good until then: a caller that
keeps it copies it). The buffers grow to what a row group and a block need and are
then used again, never made anew for each block and row group: the heap does not
fragment as a long input goes on, and a row group is never copied.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np
import numpy.typing as npt
import pyarrow as pa

from analyzer.fleet.arrow_arrays import (
    FIXED_TYPES,
    STRING,
    STRINGS,
    Bools,
    Lengths,
    TextLists,
    Texts,
    fixed,
    fixed_array,
    list_array,
    text_array,
    text_lists,
    texts,
)

_ROWS_STEP = 1024  # buffers grow to what they must hold, in steps of this many rows
_BYTES_STEP = 1 << 16  # or bytes


class Builder(Protocol):
    """The rows of one column: ``size`` of them."""

    size: int

    def append(self, values: list[Any]) -> None:
        """Python values (None is null); Unfit or OverflowError, and nothing added, when
        the column cannot take one of them."""

    def append_nulls(self, count: int) -> None: ...

    def take(self, count: int) -> pa.Array:
        """The first ``count`` rows as an array over the buffers (good until the next
        append or take); the rows after them stay."""


def builder(kind: pa.DataType) -> Builder:
    if kind == STRING:
        return TextBuilder()
    if kind == STRINGS:
        return TextListBuilder()
    return FixedBuilder(kind)


def _grown(array: npt.NDArray[Any], need: int, kept: int, step: int) -> npt.NDArray[Any]:
    """``array`` in a buffer of at least ``need`` items (a multiple of ``step``), its
    first ``kept`` items kept, the rest 0."""
    out = np.zeros(-(-need // step) * step, array.dtype)
    out[:kept] = array[:kept]
    return out


class _Rows:
    """Which rows are not null, in a buffer that grows (the base of every builder), and
    how many rows at the front were taken (dropped at the next append or take)."""

    kind: pa.DataType

    def __init__(self) -> None:
        self.size = 0
        self.valid: Bools = np.zeros(0, np.bool_)
        self.taken = 0

    def take(self, count: int) -> pa.Array:
        self._drop_taken()
        array = self._array(count) if self.valid[:count].any() else pa.nulls(count, self.kind)
        self._take(count)
        return array

    def _array(self, count: int) -> pa.Array:
        """The first ``count`` rows (some not null) as an array over the buffers."""
        raise NotImplementedError

    def _room(self, count: int) -> int:
        """Room for ``count`` more rows; the index of the first."""
        self._drop_taken()
        need = self.size + count
        if need > len(self.valid):
            self._grow(need)
        return self.size

    def _grow(self, rows: int) -> None:
        self.valid = _grown(self.valid, rows, self.size, _ROWS_STEP)

    def _add(self, count: int, valid: Bools | bool | None) -> None:
        self.valid[self.size : self.size + count] = True if valid is None else valid
        self.size += count

    def _taken_valid(self, count: int) -> Bools | None:
        """Which of the first ``count`` rows are not null (None: all)."""
        valid = self.valid[:count]
        return None if valid.all() else valid

    def _take(self, count: int) -> None:
        """The first ``count`` rows are handed out: dropped at the next append or take."""
        self._drop_taken()
        self.taken = count

    def _drop_taken(self) -> None:
        if self.taken:
            count, self.taken = self.taken, 0
            self._drop(count)

    def _drop(self, count: int) -> None:
        rest = self.size - count
        self.valid[:rest] = self.valid[count : self.size]
        self.size = rest


class FixedBuilder(_Rows):
    """Numbers, bools or timestamps: one value a row (allocated at the first value that
    is not null: the columns of other commands are null throughout)."""

    def __init__(self, kind: pa.DataType) -> None:
        super().__init__()
        self.kind = kind
        self.data: npt.NDArray[Any] | None = None

    def _grow(self, rows: int) -> None:
        super()._grow(rows)
        if self.data is not None:
            self.data = _grown(self.data, rows, self.size, _ROWS_STEP)

    def append(self, values: list[Any]) -> None:
        data, valid = fixed(values, self.kind)
        self.append_array(data, valid)

    def append_array(self, data: npt.NDArray[Any], valid: Bools | None) -> None:
        """Values as numpy (0 where ``valid`` says null; ``valid`` None: none null)."""
        at = self._room(len(data))
        if self.data is None:
            self.data = np.zeros(len(self.valid), FIXED_TYPES[self.kind])
        self.data[at : at + len(data)] = data
        self._add(len(data), valid)

    def append_nulls(self, count: int) -> None:
        at = self._room(count)
        if self.data is not None:
            self.data[at : at + count] = 0
        self._add(count, False)

    def _array(self, count: int) -> pa.Array:
        assert self.data is not None  # a row is not null
        return fixed_array(self.kind, self.data[:count], self._taken_valid(count))

    def _drop(self, count: int) -> None:
        if self.data is not None:
            self.data[: self.size - count] = self.data[count : self.size]
        super()._drop(count)


class _Sized(_Rows):
    """Rows of a size each: the bytes of a string, the items of a list (0 when null)."""

    def __init__(self) -> None:
        super().__init__()
        self.lengths: Lengths = np.zeros(0, np.int32)

    def _grow(self, rows: int) -> None:
        super()._grow(rows)
        self.lengths = _grown(self.lengths, rows, self.size, _ROWS_STEP)

    def _add_sized(self, at: int, lengths: Lengths, valid: Bools | None) -> None:
        self.lengths[at : at + len(lengths)] = lengths
        self._add(len(lengths), valid)

    def append_nulls(self, count: int) -> None:
        at = self._room(count)
        self.lengths[at : at + count] = 0
        self._add(count, False)

    def _drop(self, count: int) -> None:
        self.lengths[: self.size - count] = self.lengths[count : self.size]
        super()._drop(count)


class TextBuilder(_Sized):
    """Strings: each row's length in bytes and the bytes of every row one after the other."""

    kind = STRING

    def __init__(self) -> None:
        super().__init__()
        self.data = np.zeros(0, np.uint8)
        self.used = 0  # bytes of ``data`` that hold rows

    def append(self, values: list[Any]) -> None:
        self.append_texts(texts(values))

    def append_texts(self, values: Texts) -> None:
        at = self._room(len(values.lengths))
        size = len(values.data)
        if self.used + size > len(self.data):
            self.data = _grown(self.data, self.used + size, self.used, _BYTES_STEP)
        self.data[self.used : self.used + size] = np.frombuffer(values.data, np.uint8)
        self.used += size
        self._add_sized(at, values.lengths, values.valid)

    def take_texts(self, count: int) -> Texts:
        """The first ``count`` rows over the buffers (good until the next append or
        take); the rows after them stay."""
        self._drop_taken()
        taken = self._texts(count)
        self._take(count)
        return taken

    def _texts(self, count: int) -> Texts:
        size = int(self.lengths[:count].sum())
        return Texts(self.lengths[:count], self.data[:size], self._taken_valid(count))

    def _array(self, count: int) -> pa.Array:
        return text_array(self._texts(count))

    def _drop(self, count: int) -> None:
        size = int(self.lengths[:count].sum())
        self.data[: self.used - size] = self.data[size : self.used]
        self.used -= size
        super()._drop(count)


class TextListBuilder(_Sized):
    """Lists of strings: each row's number of items, and the items (a TextBuilder)."""

    kind = STRINGS

    def __init__(self) -> None:
        super().__init__()
        self.items = TextBuilder()

    def append(self, values: list[Any]) -> None:
        lists = text_lists(values)
        at = self._room(len(lists.lengths))
        self.items.append_texts(lists.items)
        self._add_sized(at, lists.lengths, lists.valid)

    def _array(self, count: int) -> pa.Array:
        lengths = self.lengths[:count]
        items = self.items.take_texts(int(lengths.sum()))
        return list_array(TextLists(lengths, items, self._taken_valid(count)))
