"""The rows of one input file: the same pipeline as decode and analyze, as Arrow tables.

``file_rows`` is a pure function of one file (and the settings): it runs on a local
worker process or on a Dask worker alike, and gives the same rows wherever it runs.
"""

from __future__ import annotations

import json
import os
import socket
import sys
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import pyarrow as pa

from analyzer.fleet.columns import (
    EXTRA,
    KEY_FIELDS,
    RECORDINGS,
    TIME,
    TOPIC_TABLES,
    diagnostic_column,
    event_schema,
    recordings_schema,
    verdict_column,
)
from analyzer.protocol.types import DIAGNOSTIC_KINDS, TOPIC_ANALYSIS_RESPONSE, Event

_KEYS = frozenset(f.name for f in KEY_FIELDS) | {"topic", EXTRA}
_PY_TYPES: dict[pa.DataType, tuple[type, ...]] = {
    pa.string(): (str,),
    pa.int64(): (int,),
    pa.float64(): (float, int),
    pa.bool_(): (bool,),
    pa.list_(pa.string()): (list,),
}


@dataclass(frozen=True)
class FileWork:
    """One task: a file (path or fsspec URL), its name and content hash, tags and settings."""

    path: str
    recording: str
    content_hash: str
    size_bytes: int
    tags: tuple[tuple[str, str], ...] = ()
    fmt: str | None = None
    port: int = 2000
    tolerance_deg: float | None = None
    time_allowed_s: float | None = None
    error: str | None = None  # set when the file could not even be hashed


@dataclass
class FileRows:
    """What one task gives back: a table per kind (only those with rows) and where it ran."""

    work: FileWork
    tables: dict[str, pa.Table] = field(default_factory=dict)
    error: str | None = None
    worker: str = ""
    seconds: float = 0.0
    written: bool = False  # the tables are in the dataset already (written by the worker)
    row_count: int = 0

    @property
    def rows(self) -> int:
        return self.row_count or sum(t.num_rows for t in self.tables.values())


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


class ColumnSink:
    """A pipeline sink filing every decoded event under its table (findings come apart)."""

    def __init__(self) -> None:
        self.tables: dict[str, TableColumns] = {}

    def handle(self, batch: Any) -> None:
        tables = self.tables
        for event in batch.events:
            topic = event.topic
            name = TOPIC_TABLES.get(topic)
            if name is None or topic == TOPIC_ANALYSIS_RESPONSE:
                continue
            columns = tables.get(name)
            if columns is None:
                columns = tables[name] = TableColumns(topic)
            columns.add(event.time, event.source, event.fields, event.warnings)

    def close(self) -> None:
        pass


def worker_name() -> str:
    """Where this task runs: the Dask worker's address, else host and process id."""
    if "distributed" in sys.modules:
        try:
            from distributed import get_worker

            return str(get_worker().address)
        except ValueError:
            pass
    return f"{socket.gethostname()} pid {os.getpid()}"


def file_rows(work: FileWork) -> FileRows:
    """Decode and analyse one file; a file that cannot be read is one row with its error."""
    started = time.perf_counter()
    result = FileRows(work, worker=worker_name())
    if work.error is not None:
        result.error = work.error
    else:
        try:
            with local_file(work.path) as path:
                _decode(work, path, result)
        except Exception as exc:  # any failure of one file is that file's row, not the run's
            result.tables = {}
            result.error = error_text(exc)
    if result.error is not None:
        result.tables = {RECORDINGS: recording_row(work, None, error=result.error)}
    result.seconds = time.perf_counter() - started
    return result


def error_text(exc: BaseException) -> str:
    text = str(exc).strip() or type(exc).__name__
    if type(exc).__name__ not in ("UsageError", "InputError", "SourceError"):
        text = f"{type(exc).__name__}: {text}"
    return text.splitlines()[0]


def _decode(work: FileWork, path: str, result: FileRows) -> None:
    from analyzer.analysis.response import ResponseAnalyzer, Settings
    from analyzer.commands.analyze import KeepFindings, untimed
    from analyzer.inputs import open_input
    from analyzer.pipeline import Pipeline, run_items
    from analyzer.protocol.ids import PROTOCOL_IDS
    from analyzer.summary import Summary

    knobs: dict[str, float] = {}
    if work.tolerance_deg is not None:
        knobs["tolerance_deg"] = work.tolerance_deg
    if work.time_allowed_s is not None:
        knobs["time_allowed_s"] = work.time_allowed_s
    settings = Settings(**knobs)
    reader = open_input(path, work.fmt, work.port, wanted_ids=PROTOCOL_IDS)
    analyzer = ResponseAnalyzer(settings)
    kept = KeepFindings(analyzer)
    sink = ColumnSink()
    pipeline = Pipeline([sink], stages=[kept])  # what decode, analyze and report run
    try:
        run_items(reader, pipeline)
    finally:
        reader.close()
    for failure in pipeline.failures:
        raise failure.error
    summary = Summary(work.path, reader.format_name, pipeline.tally)
    summary.finish(
        input_stats=reader.stats,
        decoder_stats=getattr(pipeline.decoder, "stats", {}),
        first_time=reader.first_time,
        last_time=reader.last_time,
        time_base=reader.time_base,
    )
    findings: list[Event] = sorted(kept.findings, key=lambda e: e.time)
    notes = list(reader.notes)
    if untimed(pipeline.tally, findings):
        findings = []
        notes.append("the input carries no timestamps: responses cannot be timed")
    found = TableColumns(TOPIC_ANALYSIS_RESPONSE)
    for finding in findings:
        found.add(finding.time, finding.source, finding.fields, finding.warnings)
    columns = dict(sink.tables)
    if findings:
        columns[TOPIC_TABLES[TOPIC_ANALYSIS_RESPONSE]] = found
    for name, gathered in columns.items():
        result.tables[name] = gathered.table(work.recording, work.content_hash)
    figures = summary.to_dict()
    verdicts: dict[str, int] = {}
    for finding in findings:
        verdict = str(finding.fields["verdict"])
        verdicts[verdict] = verdicts.get(verdict, 0) + 1
    row = {
        "source": reader.source,
        "format": reader.format_name,
        "figures": figures,
        "items": pipeline.tally.items(),
        "verdicts": verdicts,
        "findings": len(findings),
        "notes": notes,
    }
    result.tables[RECORDINGS] = recording_row(work, row)


def recording_row(work: FileWork, run: dict[str, Any] | None, error: str | None = None) -> pa.Table:
    """The one row of the recordings table for ``work`` (figures null when it failed)."""
    from analyzer import __version__

    tags = dict(work.tags)
    row: dict[str, Any] = {
        "recording": work.recording,
        "content_hash": work.content_hash,
        **tags,
        "path": work.path,
        "size_bytes": work.size_bytes,
        "analyzer_version": __version__,
        "error": error,
    }
    if run is not None:
        figures = run["figures"]
        feedback = list(figures["feedback"].values())
        first, last = figures["first_time"], figures["last_time"]
        if last is None or last <= 0:  # no clock (a raw byte dump): "no timestamps"
            first = last = None
        kinds = figures["diagnostics_by_kind"]
        rates = [f["rate_hz"] for f in feedback if f["rate_hz"] is not None]
        gaps = [f["longest_gap_s"] for f in feedback if f["longest_gap_s"] is not None]
        row.update(
            source=run["source"],
            format=run["format"],
            start=first,
            end=last,
            duration_s=figures["span_s"],
            frames=run["items"]["frames"],
            chunks=run["items"]["chunks"],
            bytes=run["items"]["bytes"],
            events=figures["events"],
            commands=figures["topics"].get("/gimbal/command", 0),
            feedback_messages=sum(f["messages"] for f in feedback)
            + figures.get("feedback_untracked", 0),
            feedback_rate_hz=rates[0] if len(rates) == 1 else (max(rates) if rates else None),
            crc_checked=figures["crc_checked"],
            crc_errors=figures["crc_errors"],
            crc_error_rate=figures["crc_error_rate"],
            gaps=sum(f["gaps_over_threshold"] for f in feedback),
            longest_gap_s=max(gaps) if gaps else None,
            diagnostics=figures["diagnostics"],
            bus_worst_state=(figures.get("bus") or {}).get("worst_state"),
            bus_worst_time=(figures.get("bus") or {}).get("worst_time"),
            findings=run["findings"],
            notes=run["notes"],
        )
        for kind in DIAGNOSTIC_KINDS:
            row[diagnostic_column(kind)] = int(kinds.get(kind, 0))
        for verdict, count in run["verdicts"].items():
            row[verdict_column(verdict)] = count
        from analyzer.analysis.findings import VERDICTS

        for verdict in VERDICTS:
            row.setdefault(verdict_column(verdict), 0)
    schema = recordings_schema(list(tags))
    for name in ("start", "end", "bus_worst_time"):
        value = row.get(name)
        row[name] = None if value is None else round(float(value) * 1_000_000)
    columns = {
        f.name: pa.array([row.get(f.name)], pa.int64() if f.type == TIME else f.type).cast(f.type)
        for f in schema
    }
    return pa.Table.from_pydict(columns, schema=schema)


@contextmanager
def local_file(path: str) -> Iterator[str]:
    """A local path for ``path``: itself, or a temporary copy of an fsspec URL (s3://...)."""
    if "://" not in path:
        yield path
        return
    import shutil
    import tempfile

    import fsspec

    suffix = "".join(os.path.basename(path).partition(".")[1:])
    with tempfile.TemporaryDirectory(prefix="gimbal-fleet-") as tmp:
        local = os.path.join(tmp, "input" + ("." + suffix.lstrip(".") if suffix else ""))
        with fsspec.open(path, "rb") as remote, open(local, "wb") as out:
            shutil.copyfileobj(remote, out, 1 << 20)
        yield local
