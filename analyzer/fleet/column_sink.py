"""Decoded events and findings into typed Arrow columns, a Parquet row group at a time.

``ColumnSink`` is a pipeline sink: it files each event under its fleet table and hands
a table's rows on (to ``TablesOut``: the dataset's files, or the caller) every
``GROUP_ROWS`` rows, so memory holds one row group per table, never an input's rows.
"""

from __future__ import annotations

import json
from collections import Counter
from collections.abc import Sequence
from typing import Any, Protocol

import pyarrow as pa

from analyzer.fleet.columns import EXTRA, KEY_FIELDS, TIME, TOPIC_TABLES, event_schema
from analyzer.protocol.response_fields import FEEDBACK_COMMAND
from analyzer.protocol.types import TOPIC_ANALYSIS_RESPONSE

GROUP_ROWS = 16_384  # rows of one Parquet row group: what a table holds in memory at most
_KEYS = frozenset(f.name for f in KEY_FIELDS) | {"topic", EXTRA}
_PY_TYPES: dict[pa.DataType, tuple[type, ...]] = {
    pa.string(): (str,),
    pa.int64(): (int,),
    pa.float64(): (float, int),
    pa.bool_(): (bool,),
    pa.list_(pa.string()): (list,),
}


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

    def clear(self) -> None:
        self.times.clear()
        self.sources.clear()
        for values in self.columns.values():
            values.clear()
        self.extra.clear()

    def table(self, recording: str, content_hash: str) -> pa.Table:
        n = len(self.times)
        arrays: list[pa.Array] = [
            pa.array([recording] * n, pa.string()),
            pa.array([content_hash] * n, pa.string()),
            timestamps(self.times),
            pa.array(self.sources, pa.string()),
        ]
        for name in self.names:
            arrays.append(self._column(name, self.schema.field(name).type))
        arrays.append(
            pa.array(
                [None if e is None else json.dumps(e, default=str) for e in self.extra], pa.string()
            )
        )
        return pa.Table.from_arrays(arrays, schema=self.schema)

    def _column(self, name: str, kind: pa.DataType) -> pa.Array:
        values = self.columns[name]
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
    """Unix seconds -> UTC timestamps in microseconds."""
    micros = [None if s is None else round(s * 1_000_000) for s in seconds]
    return pa.array(micros, pa.int64()).cast(TIME)


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

    keeps_items = False  # events only: the reader may hand its frames on as runs

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
        tables = self.tables
        for event in batch.events:
            topic = event.topic
            name = TOPIC_TABLES.get(topic)
            if name is None:
                continue
            if topic == TOPIC_ANALYSIS_RESPONSE:
                fields = event.fields
                counts = self.health if fields.get("command") == FEEDBACK_COMMAND else self.verdicts
                counts[str(fields["verdict"])] += 1
                self.findings += 1
            columns = tables.get(name)
            if columns is None:
                columns = tables[name] = TableColumns(topic)
            columns.add(event.time, event.source, event.fields, event.warnings)
            if len(columns.times) >= self.group_rows:
                self._flush(name, columns)

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
        table = columns.table(self.recording, self.content_hash)
        columns.clear()
        self.rows += table.num_rows
        self.out.write(name, table)
