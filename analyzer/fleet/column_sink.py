"""Decoded events and findings into typed Arrow columns, a Parquet row group at a time.

``ColumnSink`` is a pipeline sink: it files each event under its fleet table and hands
a table's rows on (to ``TablesOut``: the dataset's files, or the caller) every
``GROUP_ROWS`` rows, so memory holds one row group per table, never an input's rows.
Events decoded in vectors come to it as columns (``takes_columns``) and go into the
tables a column at a time, in the order of the frames that gave them.
"""

from __future__ import annotations

import json
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from operator import itemgetter
from typing import Any, Protocol

import pyarrow as pa

from analyzer.fleet.columns import EXTRA, KEY_FIELDS, TIME, TOPIC_TABLES, event_schema
from analyzer.protocol.event_columns import EventColumns, EventGroup
from analyzer.protocol.response_fields import FEEDBACK_COMMAND
from analyzer.protocol.types import TOPIC_ANALYSIS_RESPONSE, Event

GROUP_ROWS = 16_384  # rows of one Parquet row group: what a table holds in memory at most
_KEYS = frozenset(f.name for f in KEY_FIELDS) | {"topic", EXTRA}
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
    """Events of one topic gathered column by column, typed by the topic's schema."""

    def __init__(self, topic: str) -> None:
        self.schema = event_schema(topic)
        self.names = [f.name for f in self.schema if f.name not in _KEYS]
        self.known = frozenset(self.names) | _KEYS
        self.times: list[float] = []
        self.sources: list[str] = []
        self.columns: dict[str, list[Any]] = {name: [] for name in self.names}
        self.extra: list[dict[str, Any] | None] = []

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

    def empty(self) -> TableColumns:
        """A table of the same topic with no rows (its schema not made again)."""
        other = TableColumns.__new__(TableColumns)
        other.schema, other.names, other.known = self.schema, self.names, self.known
        other.times, other.sources, other.extra = [], [], []
        other.columns = {name: [] for name in self.names}
        return other

    def event_part(self, event: Event) -> Part:
        """One event as a part: what ``add`` makes of it."""
        one = self.empty()
        one.add(event.time, event.source, event.fields, event.warnings)
        return Part(one.times, one.sources, one.columns, one.extra)

    def split(self, count: int) -> TableColumns:
        """The first ``count`` rows, taken out as a table of their own."""
        first = self.empty()
        first.times, self.times = self.times[:count], self.times[count:]
        first.sources, self.sources = self.sources[:count], self.sources[count:]
        first.extra, self.extra = self.extra[:count], self.extra[count:]
        for name, values in self.columns.items():
            first.columns[name], self.columns[name] = values[:count], values[count:]
        return first

    def clear(self) -> None:
        self.times.clear()
        self.sources.clear()
        for values in self.columns.values():
            values.clear()
        self.extra.clear()

    def table(self, recording: str, content_hash: str) -> pa.Table:
        n = len(self.times)
        arrays: list[pa.Array] = [
            pa.repeat(pa.scalar(recording, pa.string()), n),
            pa.repeat(pa.scalar(content_hash, pa.string()), n),
            timestamps(self.times),
            pa.array(self.sources, pa.string()),
        ]
        for name in self.names:
            arrays.append(self._column(name, self.schema.field(name).type))
        extra = self.extra
        if extra.count(None) == n:  # the usual table: every field has its column
            arrays.append(pa.nulls(n, pa.string()))
        else:
            texts = [None if e is None else json.dumps(e, default=str) for e in extra]
            arrays.append(pa.array(texts, pa.string()))
        return pa.Table.from_arrays(arrays, schema=self.schema)

    def _column(self, name: str, kind: pa.DataType) -> pa.Array:
        values = self.columns[name]
        if values.count(None) == len(values):  # a field of other commands: null throughout
            return pa.nulls(len(values), kind)
        try:
            return pa.array(values, kind)
        except (pa.ArrowInvalid, pa.ArrowTypeError, TypeError, OverflowError):
            pass
        # A value of another type than the schema says: kept in ``extra``, never lost.
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
        return pa.array(values, kind)


def _bool_as_number(value: Any, kind: pa.DataType) -> bool:
    return isinstance(value, bool) and kind != pa.bool_()


def timestamps(seconds: Sequence[float | None]) -> pa.Array:
    """Unix seconds -> UTC timestamps in microseconds (rounded half to even, as ``round``)."""
    if None in seconds:
        micros = [None if s is None else round(s * 1_000_000) for s in seconds]
        return pa.array(micros, pa.int64()).cast(TIME)
    import numpy as np  # pyarrow's own dependency

    exact = np.rint(np.array(seconds, np.float64) * 1_000_000).astype(np.int64)
    return pa.array(exact, pa.int64()).cast(TIME)


class TablesOut(Protocol):
    """Where an input's row groups go: files of the dataset, or back to the caller."""

    def write(self, name: str, table: pa.Table) -> None: ...

    def discard(self, name: str) -> None: ...


class CollectedTables:
    """Row groups kept for the caller (a Dask worker sending its rows back)."""

    def __init__(self) -> None:
        self.parts: dict[str, list[pa.Table]] = {}

    def write(self, name: str, table: pa.Table) -> None:
        self.parts.setdefault(name, []).append(table)

    def discard(self, name: str) -> None:
        self.parts.pop(name, None)

    def tables(self) -> dict[str, pa.Table]:
        return {name: pa.concat_tables(parts) for name, parts in self.parts.items()}


class ColumnSink:
    """A pipeline sink filing every decoded event and finding under its table, a row group
    at a time into ``out`` as the rows come (memory: one row group per table)."""

    keeps_items = False  # events only: frames read as columns are never made one by one
    takes_columns = True  # blocks decoded in vectors come as columns (``handle_columns``)

    def __init__(
        self, out: TablesOut, recording: str, content_hash: str, group_rows: int | None = None
    ) -> None:
        self.out = out
        self.recording = recording
        self.content_hash = content_hash
        self.group_rows = group_rows or GROUP_ROWS
        self.tables: dict[str, TableColumns] = {}
        self.rows = 0
        self.findings = 0
        self.verdicts: Counter[str] = Counter()  # of the commands' findings
        self.health: Counter[str] = Counter()  # of the feedback's findings (health words)

    def handle(self, batch: Any) -> None:
        for segment in batch.segments():
            if isinstance(segment, EventColumns):
                self.handle_columns(segment)
                continue
            for event in segment:
                name = TOPIC_TABLES.get(event.topic)
                if name is None:
                    continue
                if event.topic == TOPIC_ANALYSIS_RESPONSE:
                    self._count_finding(event)
                columns = self._table(name, event.topic)
                columns.add(event.time, event.source, event.fields, event.warnings)
                if len(columns.times) >= self.group_rows:
                    self._flush(name, columns)

    def handle_columns(self, block: EventColumns) -> None:
        """The events of a block decoded in vectors, a table's rows at a time, each
        table's in the order of the frames that gave them."""
        parts: dict[str, list[tuple[list[int], Part]]] = {}
        for group in block.groups:
            name = TOPIC_TABLES.get(group.topic)
            if name is not None:
                part = self._table(name, group.topic).group_part(group)
                parts.setdefault(name, []).append((group.rows.tolist(), part))
        for row, event in block.single_events():
            name = TOPIC_TABLES.get(event.topic)
            if name is not None:
                columns = self._table(name, event.topic)
                parts.setdefault(name, []).append(([row], columns.event_part(event)))
        for name, pieces in parts.items():
            columns = self.tables[name]
            columns.extend(_in_frame_order(columns.names, pieces))
            while len(columns.times) >= self.group_rows:
                self._write(name, columns.split(self.group_rows))

    def _table(self, name: str, topic: str) -> TableColumns:
        columns = self.tables.get(name)
        if columns is None:
            columns = self.tables[name] = TableColumns(topic)
        return columns

    def _count_finding(self, event: Event) -> None:
        fields = event.fields
        counts = self.health if fields.get("command") == FEEDBACK_COMMAND else self.verdicts
        counts[str(fields["verdict"])] += 1
        self.findings += 1

    def close(self) -> None:
        for name, columns in self.tables.items():
            if columns.times:
                self._flush(name, columns)

    def drop_findings(self) -> None:
        """Forget every finding written (an input without a clock cannot time them)."""
        name = TOPIC_TABLES[TOPIC_ANALYSIS_RESPONSE]
        self.out.discard(name)
        self.rows -= self.findings
        self.findings = 0
        self.verdicts.clear()
        self.health.clear()
        self.tables.pop(name, None)

    def _flush(self, name: str, columns: TableColumns) -> None:
        self._write(name, columns)
        columns.clear()

    def _write(self, name: str, columns: TableColumns) -> None:
        table = columns.table(self.recording, self.content_hash)
        self.rows += table.num_rows
        self.out.write(name, table)


def _in_frame_order(names: list[str], pieces: list[tuple[list[int], Part]]) -> Part:
    """The parts of one table as one, their rows in the order of their frames."""
    if len(pieces) == 1:
        return pieces[0][1]
    rows = [row for at, _ in pieces for row in at]
    order = sorted(range(len(rows)), key=rows.__getitem__)
    pick = itemgetter(*order)
    parts = [part for _, part in pieces]

    def ordered(values: list[Any]) -> list[Any]:
        return list(pick(values)) if len(values) > 1 else values

    columns: dict[str, list[Any]] = {}
    for name in names:
        if any(name in p.columns for p in parts):  # else null in every row
            columns[name] = ordered([v for p in parts for v in p.column(name)])
    return Part(
        ordered([t for p in parts for t in p.times]),
        ordered([s for p in parts for s in p.sources]),
        columns,
        ordered([e for p in parts for e in p.extra]),
    )
