"""Decoded events and findings into typed Arrow columns, a Parquet row group at a time.

``ColumnSink`` is a pipeline sink: it files each event under its fleet table and hands
a table's rows on (to ``TablesOut``: the dataset's files, or the caller) every
``GROUP_ROWS`` rows, so memory holds one row group per table, never an input's rows.
Events decoded in vectors come to it as columns (``takes_columns``) and go into the
tables a column at a time, in the order of the frames that gave them. A table keeps at
most ``CHUNK_ROWS`` rows as Python values; then they go into numpy buffers that stay
from row group to row group (``table_columns``), and Arrow arrays are made of those
(``arrow_arrays``: ``pa.array`` would import pandas).
"""

from __future__ import annotations

from collections import Counter
from operator import itemgetter
from typing import Any, Protocol

import pyarrow as pa

from analyzer.fleet.arrow_arrays import repeated
from analyzer.fleet.columns import TOPIC_TABLES
from analyzer.fleet.table_columns import Part, TableColumns
from analyzer.protocol.event_columns import EventColumns
from analyzer.protocol.response_fields import FEEDBACK_COMMAND
from analyzer.protocol.types import TOPIC_ANALYSIS_RESPONSE, Event

GROUP_ROWS = 16_384  # rows of one Parquet row group: what a table holds in memory at most
CHUNK_ROWS = 1_024  # rows a table holds as Python values before they go into its buffers


class TablesOut(Protocol):
    """Where an input's row groups go: files of the dataset, or back to the caller."""

    def write(self, name: str, table: pa.Table) -> None:
        """One row group of table ``name``. Its arrays are over the sink's buffers, good
        until ``write`` returns: one that keeps the rows keeps a copy."""

    def discard(self, name: str) -> None: ...


class CollectedTables:
    """Row groups kept for the caller (a Dask worker sending its rows back)."""

    def __init__(self) -> None:
        self.parts: dict[str, list[pa.Table]] = {}

    def write(self, name: str, table: pa.Table) -> None:
        # concat_arrays copies the rows out of the sink's buffers
        copy = [pa.concat_arrays(column.chunks) for column in table.columns]
        self.parts.setdefault(name, []).append(pa.Table.from_arrays(copy, schema=table.schema))

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
        self._group_keys: list[pa.Array] | None = None
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
                self._written(name, columns)

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
            self._written(name, columns)

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
            if columns.rows:
                self._write(name, columns, columns.rows)

    def drop_findings(self) -> None:
        """Forget every finding written (an input without a clock cannot time them)."""
        name = TOPIC_TABLES[TOPIC_ANALYSIS_RESPONSE]
        self.out.discard(name)
        self.rows -= self.findings
        self.findings = 0
        self.verdicts.clear()
        self.health.clear()
        self.tables.pop(name, None)

    def _written(self, name: str, columns: TableColumns) -> None:
        """Every whole row group of the table written; the rows held as Python values
        made Arrow arrays when they are many."""
        while columns.rows >= self.group_rows:
            self._write(name, columns, self.group_rows)
        if len(columns.times) >= CHUNK_ROWS:
            columns.settle()

    def _write(self, name: str, columns: TableColumns, count: int) -> None:
        table = columns.take(count, self._keys(count))
        self.rows += table.num_rows
        self.out.write(name, table)

    def _keys(self, count: int) -> list[pa.Array]:
        """The recording's name and content hash in each of ``count`` rows (those of a
        whole row group made once)."""
        keys = self._group_keys if count == self.group_rows else None
        if keys is None:
            keys = [repeated(self.recording, count), repeated(self.content_hash, count)]
            if count == self.group_rows:
                self._group_keys = keys
        return keys


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
