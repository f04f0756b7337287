"""The rows of one fleet table on their way to a row group: Python values, then numpy buffers.

Events come one by one (``add``) or as columns of a block decoded in vectors
(``group_part``, ``extend``) and are kept as Python values; ``settle`` converts them
into the table's column builders (numpy buffers that stay, ``column_builders``), and
``take`` gives a row group as an Arrow table. A value of another type than the
schema's column is kept in the row's ``extra`` (JSON), never lost.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pyarrow as pa

from analyzer.fleet.arrow_arrays import Bools, Unfit, fixed
from analyzer.fleet.column_builders import Builder, FixedBuilder, TextBuilder, builder
from analyzer.fleet.columns import EXTRA, KEY_FIELDS, TIME, event_schema
from analyzer.protocol.event_columns import EventGroup
from analyzer.protocol.types import Event

_KEYS = frozenset(f.name for f in KEY_FIELDS) | {"topic", EXTRA}
# What the schema's types keep of a row's values; any other goes into ``extra``.
_PY_TYPES: dict[pa.DataType, tuple[type, ...]] = {
    pa.string(): (str,),
    pa.int64(): (int,),
    pa.float64(): (float, int),
    pa.bool_(): (bool,),
    pa.list_(pa.string()): (list,),
}


@dataclass(slots=True)
class Part:
    """Rows of one table as columns: times, sources, values by column (a column not
    named is null in every row) and each row's ``extra`` fields."""

    times: list[float]
    sources: list[str]
    columns: dict[str, list[Any]]
    extra: list[dict[str, Any] | None]

    def column(self, name: str) -> list[Any]:
        values = self.columns.get(name)
        return [None] * len(self.times) if values is None else values


class TableColumns:
    """Events of one topic gathered column by column, typed by the topic's schema: the
    latest rows as Python values (``times``, ``sources``, ``columns``, ``extra``), the
    ``settled`` rows before them in the column builders."""

    def __init__(self, topic: str) -> None:
        self.schema = event_schema(topic)
        self.names = [f.name for f in self.schema if f.name not in _KEYS]
        self.known = frozenset(self.names) | _KEYS
        self.times: list[float] = []
        self.sources: list[str] = []
        self.columns: dict[str, list[Any]] = {name: [] for name in self.names}
        self.extra: list[dict[str, Any] | None] = []
        self.settled = 0
        self._time = FixedBuilder(TIME)
        self._source = TextBuilder()
        self._fields: dict[str, Builder] = {}
        self._extra = TextBuilder()

    @property
    def rows(self) -> int:
        """Rows held, as Python values or in the builders."""
        return self.settled + len(self.times)

    def add(self, time_s: float, source: str, fields: dict[str, Any], warnings: list[str]) -> None:
        self.times.append(time_s)
        self.sources.append(source)
        columns = self.columns
        for name in self.names:
            columns[name].append(fields.get(name))
        if "warnings" in columns:
            columns["warnings"][-1] = list(warnings)
        unknown = fields.keys() - self.known
        self.extra.append({k: fields[k] for k in sorted(unknown)} if unknown else None)

    def extend(self, part: Part) -> None:
        """Rows as columns (what ``add`` makes of each of their events)."""
        self.times += part.times
        self.sources += part.sources
        for name, values in self.columns.items():
            values += part.column(name)
        self.extra += part.extra

    def group_part(self, group: EventGroup) -> Part:
        """The rows of a group of events decoded in vectors (none has a warning)."""
        n = len(group)
        values = group.values()
        constants = group.constants
        columns: dict[str, list[Any]] = {}
        for name in self.names:
            if name in constants:
                columns[name] = [constants[name]] * n
            elif name in values:
                columns[name] = values[name]
        if "warnings" in self.columns:
            columns["warnings"] = [[]] * n  # one empty list: never changed, only read
        unknown = sorted(k for k in group.keys if k not in self.known)
        extra: list[dict[str, Any] | None] = [None] * n
        if unknown:
            cells = [[constants[k]] * n if k in constants else values[k] for k in unknown]
            extra = [dict(zip(unknown, row, strict=True)) for row in zip(*cells, strict=True)]
        return Part(group.times.tolist(), list(group.sources), columns, extra)

    def event_part(self, event: Event) -> Part:
        """One event as a part: what ``add`` makes of it."""
        one = TableColumns.__new__(TableColumns)
        one.names, one.known = self.names, self.known
        one.times, one.sources, one.extra = [], [], []
        one.columns = {name: [] for name in self.names}
        one.add(event.time, event.source, event.fields, event.warnings)
        return Part(one.times, one.sources, one.columns, one.extra)

    def clear(self) -> None:
        self.times.clear()
        self.sources.clear()
        for values in self.columns.values():
            values.clear()
        self.extra.clear()

    def settle(self) -> None:
        """The rows held as Python values go into the builders, after those before them."""
        n = len(self.times)
        if not n:
            return
        self._time.append_array(*micros(self.times))
        self._source.append(self.sources)
        for name in self.names:
            self._settle_column(name, n)
        extra = self.extra
        if extra.count(None) == n:  # the usual table: every field has its column
            self._extra.append_nulls(n)
        else:
            self._extra.append([None if e is None else json.dumps(e, default=str) for e in extra])
        self.settled += n
        self.clear()

    def _settle_column(self, name: str, n: int) -> None:
        values = self.columns[name]
        column = self._fields.get(name)
        if column is None:
            column = self._fields[name] = builder(self.schema.field(name).type)
            column.append_nulls(self.settled)
        if values.count(None) == n:  # a field of other commands: null throughout
            column.append_nulls(n)
            return
        try:
            column.append(values)
            return
        except (Unfit, OverflowError):
            pass
        # A value of another type than the schema says: kept in ``extra``, never lost.
        kind = self.schema.field(name).type
        wanted = _PY_TYPES.get(kind, (object,))
        for i, value in enumerate(values):
            if value is None or (isinstance(value, wanted) and not _bool_as_number(value, kind)):
                continue
            extra = self.extra[i]
            if extra is None:
                extra = {}
            extra[name] = value
            self.extra[i] = extra
            values[i] = None
        column.append(values)

    def take(self, count: int, keys: list[pa.Array]) -> pa.Table:
        """The first ``count`` rows as a table of the schema (``keys``: the columns of one
        value throughout, recording and content hash); the rows after them stay."""
        self.settle()
        arrays = [*keys, self._time.take(count), self._source.take(count)]
        for name in self.names:
            column = self._fields.get(name)
            arrays.append(column.take(count) if column else pa.nulls(count, self._kind(name)))
        arrays.append(self._extra.take(count))
        self.settled -= count
        return pa.Table.from_arrays(arrays, schema=self.schema)

    def _kind(self, name: str) -> pa.DataType:
        return self.schema.field(name).type


def _bool_as_number(value: Any, kind: pa.DataType) -> bool:
    return isinstance(value, bool) and kind != pa.bool_()


def micros(seconds: Sequence[float | None]) -> tuple[np.ndarray[Any, Any], Bools | None]:
    """Unix seconds -> microseconds (rounded half to even, as ``round``) and which are not
    None (None: all)."""
    if None in seconds:
        return fixed([None if s is None else round(s * 1_000_000) for s in seconds], TIME)
    return np.rint(np.array(seconds, np.float64) * 1_000_000).astype(np.int64), None
