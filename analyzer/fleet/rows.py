"""The rows of one input file: the same pipeline as decode and analyze, as Arrow tables.

``file_rows`` is a function of one file (and the settings) and where its rows go: it
runs on a local worker process or on a Dask worker alike, and gives the same rows
wherever it runs.
"""

from __future__ import annotations

import os
import socket
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import pyarrow as pa

from analyzer.fleet.arrow_arrays import column
from analyzer.fleet.column_sink import CollectedTables, ColumnSink, TablesOut
from analyzer.fleet.columns import (
    RECORDINGS,
    diagnostic_column,
    health_column,
    recordings_schema,
    verdict_column,
)
from analyzer.output_file import OutputWriteError
from analyzer.protocol.types import DIAGNOSTIC_KINDS
from analyzer.version import __version__


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
    flag_allowed_s: float | None = None
    progress: bool = False  # a progress line while it is read (in this process, a terminal)
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


def worker_name() -> str:
    """Where this task runs: the Dask worker's address, else host and process id."""
    if "distributed" in sys.modules:
        try:
            from distributed import get_worker

            return str(get_worker().address)
        except ValueError:
            pass
    return f"{socket.gethostname()} pid {os.getpid()}"


def file_rows(work: FileWork, out: TablesOut | None = None) -> FileRows:
    """Decode and analyse one file; a file that cannot be read is one row with its error.

    The event and finding rows go to ``out`` as they come (default: kept and returned in
    ``tables``); the ``recordings`` row is returned, for the caller to write last.
    """
    started = time.perf_counter()
    result = FileRows(work, worker=worker_name())
    kept = CollectedTables()
    target: TablesOut = out if out is not None else kept
    if work.error is not None:
        result.error = work.error
    else:
        try:
            with local_file(work.path) as path:
                _decode(work, path, result, target)
        except OutputWriteError:  # the dataset cannot be written: the run stops
            raise
        except Exception as exc:  # any failure of one file is that file's row, not the run's
            result.error = error_text(exc)
    if result.error is not None:
        result.tables = {RECORDINGS: recording_row(work, None, error=result.error)}
        result.row_count = 1
    elif out is None:
        result.tables.update(kept.tables())
    result.seconds = time.perf_counter() - started
    return result


def error_text(exc: BaseException) -> str:
    """One line for the user: the message, never the exception's class name."""
    text = str(exc).strip()
    if not text:
        text = _ERROR_WORDS.get(type(exc).__name__, "failed without a message")
    return text.splitlines()[0]


_ERROR_WORDS = {
    "MemoryError": "out of memory",
    "RecursionError": "too deeply nested",
    "EOFError": "ended too early",
}


def _decode(work: FileWork, path: str, result: FileRows, out: TablesOut) -> None:
    from analyzer.analysis.findings import untimed
    from analyzer.analysis.response import Settings
    from analyzer.analysis.stage import Analysis
    from analyzer.inputs import open_input
    from analyzer.pipeline import Pipeline, run_reader
    from analyzer.progress import Progress
    from analyzer.protocol.ids import PROTOCOL_IDS
    from analyzer.summary import Summary

    knobs: dict[str, float] = {}
    if work.tolerance_deg is not None:
        knobs["tolerance_deg"] = work.tolerance_deg
    if work.time_allowed_s is not None:
        knobs["time_allowed_s"] = work.time_allowed_s
    if work.flag_allowed_s is not None:
        knobs["flag_allowed_s"] = work.flag_allowed_s
    settings = Settings(**knobs)
    reader = open_input(path, work.fmt, work.port, wanted_ids=PROTOCOL_IDS)
    sink = ColumnSink(out, work.recording, work.content_hash)
    # What decode, analyze and report run; findings reach the sink as they are made. The
    # camera commands are not judged here: a fleet's video is not decoded file by file.
    pipeline = Pipeline([sink], stages=Analysis(settings).stages())
    progress = Progress.maybe(reader, sys.stderr, quiet=not work.progress)
    run_reader(reader, pipeline, progress=progress)
    summary = Summary(work.path, reader.format_name, pipeline.tally)
    summary.finish(
        input_stats=reader.stats,
        decoder_stats=getattr(pipeline.decoder, "stats", {}),
        first_time=pipeline.clock.bounded(reader.first_time),
        last_time=reader.last_time,
        time_base=reader.time_base,
    )
    notes = list(reader.notes)
    if untimed(pipeline.tally, [True] if sink.findings else []):
        sink.drop_findings()
        notes.append("the input carries no timestamps: responses cannot be timed")
    row = {
        "source": reader.source,
        "format": reader.format_name,
        "figures": summary.to_dict(),
        "items": pipeline.tally.items(),
        "verdicts": dict(sink.verdicts),
        "health": dict(sink.health),
        "findings": sink.findings,
        "notes": notes,
    }
    result.tables[RECORDINGS] = recording_row(work, row)
    result.row_count = sink.rows + 1


def recording_row(work: FileWork, run: dict[str, Any] | None, error: str | None = None) -> pa.Table:
    """The one row of the recordings table for ``work`` (figures null when it failed)."""
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
        from analyzer.analysis.findings import HEALTH_VERDICTS, VERDICTS

        for verdict in VERDICTS:
            row[verdict_column(verdict)] = int(run["verdicts"].get(verdict, 0))
        for health in HEALTH_VERDICTS:
            row[health_column(health)] = int(run.get("health", {}).get(health, 0))
    schema = recordings_schema(list(tags))
    for name in ("start", "end", "bus_worst_time"):
        value = row.get(name)
        row[name] = None if value is None else round(float(value) * 1_000_000)
    columns = [column([row.get(f.name)], f.type) for f in schema]
    return pa.Table.from_arrays(columns, schema=schema)


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
