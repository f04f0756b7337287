"""The fleet dataset on disk: one Parquet file per table and input, named by content hash.

``DIR/<table>/<content_hash>.parquet`` holds the rows one input gave that table. Every file
is written under a temporary name and renamed into place (atomic on POSIX), and the
``recordings`` file of an input is written last: an input whose ``recordings`` file exists
is complete, and that set of hashes is the index that makes runs incremental. Files of an
input without its ``recordings`` file (a run killed half way) are removed by the next run.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import uuid
from collections.abc import Iterable
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from analyzer.errors import UsageError
from analyzer.fleet.arrow_arrays import repeated
from analyzer.fleet.columns import RECORDINGS, TABLES, recordings_schema
from analyzer.output_file import OutputWriteError, describe_os_error

SUFFIX = ".parquet"
UNREADABLE = "unreadable-"  # key prefix of a file that could not be read (by its path)
_PARTIAL = ".partial-"
HASH_BLOCK = 1 << 20
COMPRESSION = "zstd"


def content_hash(path: str) -> str:
    """SHA-256 of a file's bytes (a local path or an fsspec URL), hex."""
    digest = hashlib.sha256()
    if "://" in path:
        import fsspec

        with fsspec.open(path, "rb") as handle:
            while block := handle.read(HASH_BLOCK):
                digest.update(block)
        return digest.hexdigest()
    with open(path, "rb") as handle:
        while block := handle.read(HASH_BLOCK):
            digest.update(block)
    return digest.hexdigest()


def unreadable_hash(path: str) -> str:
    """A stand-in hash for a file that could not be read: named after its path, so the next
    run knows it failed (and skips it, unless told to retry)."""
    return UNREADABLE + hashlib.sha256(os.path.abspath(path).encode()).hexdigest()[:32]


class Dataset:
    """A fleet directory: which inputs it holds, and writing an input's tables into it."""

    def __init__(self, root: str | os.PathLike[str]) -> None:
        self.root = Path(root)

    def create(self) -> None:
        if self.root.exists() and not self.root.is_dir():
            raise UsageError(f"{self.root} exists and is not a directory")
        try:
            for name in TABLES:
                (self.root / name).mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise OutputWriteError(f"cannot create {self.root}: {describe_os_error(exc)}") from exc

    def hashes(self) -> set[str]:
        """Content hashes of the inputs the dataset holds completely."""
        folder = self.root / RECORDINGS
        if not folder.is_dir():
            return set()
        return {
            p.name[: -len(SUFFIX)]
            for p in folder.iterdir()
            if p.name.endswith(SUFFIX) and not p.name.startswith(".")
        }

    def holds(self, digest: str) -> bool:
        """True when an input of this content (or this unreadable path) is complete here."""
        return self.path(RECORDINGS, digest).exists()

    def failure(self, digest: str) -> str | None:
        """The error of the input's row (None when it was read, or is not here)."""
        try:
            column = _read(self.path(RECORDINGS, digest), ["error"]).column(0)
        except (OSError, pa.ArrowException):
            return None
        return None if len(column) == 0 else column[0].as_py()

    def tags(self, digest: str) -> dict[str, str] | None:
        """The tags of the input's row (None when it is not here)."""
        base = set(recordings_schema([]).names)
        try:
            with pq.ParquetFile(self.path(RECORDINGS, digest)) as handle:
                if handle.metadata.num_rows == 0:
                    return None
                names = [n for n in handle.schema_arrow.names if n not in base]
                table = handle.read(columns=names)  # strings only: a timestamp loads pandas
        except (OSError, pa.ArrowException):
            return None
        row = table.slice(0, 1).to_pylist()[0] if names else {}
        return {k: str(v) for k, v in row.items() if v is not None}

    def retag(self, digest: str, tags: dict[str, str]) -> None:
        """Give the input's row these tags instead of its own (rewritten atomically)."""
        target = self.path(RECORDINGS, digest)
        old = _read(target)
        schema = recordings_schema(list(tags))
        columns = [
            repeated(tags[f.name], old.num_rows)
            if f.name in tags
            else _as(old.column(f.name), f.type)
            if f.name in old.column_names
            else pa.nulls(old.num_rows, f.type)
            for f in schema
        ]
        self._write_one(target, pa.Table.from_arrays(columns, schema=schema))

    def forget(self, digest: str) -> None:
        """Remove an input's files, its ``recordings`` row first (to be made again)."""
        for name in (RECORDINGS, *(n for n in TABLES if n != RECORDINGS)):
            try:
                self.path(name, digest).unlink(missing_ok=True)
            except OSError as exc:
                raise OutputWriteError(
                    f"cannot remove {self.path(name, digest)}: {describe_os_error(exc)}"
                ) from exc

    def scratch(self, name: str) -> Path:
        """A temporary file's path in the dataset (removed by the next run if left)."""
        return self.root / RECORDINGS / f"{_PARTIAL}{name}"

    def path(self, table: str, digest: str) -> Path:
        return self.root / table / f"{digest}{SUFFIX}"

    def files(self, table: str) -> list[Path]:
        folder = self.root / table
        if not folder.is_dir():
            return []
        return sorted(p for p in folder.glob(f"*{SUFFIX}") if not p.name.startswith("."))

    def remove_partial(self) -> int:
        """Remove what a killed run left: temporary files, tables of an unfinished input."""
        complete = self.hashes()
        removed = 0
        for name in TABLES:
            folder = self.root / name
            if not folder.is_dir():
                continue
            for p in folder.iterdir():
                stem = p.name[: -len(SUFFIX)] if p.name.endswith(SUFFIX) else None
                if p.name.startswith(_PARTIAL) or (
                    name != RECORDINGS and stem is not None and stem not in complete
                ):
                    p.unlink(missing_ok=True)
                    removed += 1
        return removed

    def write(self, digest: str, tables: dict[str, pa.Table]) -> None:
        """Write an input's tables, ``recordings`` last, each by an atomic rename."""
        order: Iterable[str] = [n for n in tables if n != RECORDINGS] + [RECORDINGS]
        for name in order:
            if name not in tables:
                continue
            self._write_one(self.path(name, digest), tables[name])

    def stream(self, digest: str) -> StreamedTables:
        """Row groups of an input's tables (all but ``recordings``), written as they come."""
        return StreamedTables(self, digest)

    @staticmethod
    def _write_one(target: Path, table: pa.Table) -> None:
        temp = _temp_name(target)
        try:
            pq.write_table(table, temp, compression=COMPRESSION)
            _publish(temp, target)
        except OSError as exc:
            temp.unlink(missing_ok=True)
            raise OutputWriteError(f"cannot write {target}: {describe_os_error(exc)}") from exc


class StreamedTables:
    """An input's tables written row group by row group under temporary names
    (``ParquetWriter``), renamed into place by ``finish``, removed by ``abort``: memory
    holds one row group per table, never the input's rows."""

    def __init__(self, dataset: Dataset, digest: str) -> None:
        self.dataset = dataset
        self.digest = digest
        self.open: dict[str, tuple[pq.ParquetWriter, Path]] = {}

    def write(self, name: str, table: pa.Table) -> None:
        """One row group of table ``name`` (opened at its first)."""
        entry = self.open.get(name)
        try:
            if entry is None:
                temp = _temp_name(self.dataset.path(name, self.digest))
                entry = self.open[name] = (
                    pq.ParquetWriter(temp, table.schema, compression=COMPRESSION),
                    temp,
                )
            entry[0].write_table(table, row_group_size=max(1, table.num_rows))
        except OSError as exc:
            target = self.dataset.path(name, self.digest)
            raise OutputWriteError(f"cannot write {target}: {describe_os_error(exc)}") from exc

    def discard(self, name: str) -> None:
        """Throw away what was written of table ``name``."""
        entry = self.open.pop(name, None)
        if entry is not None:
            entry[0].close()
            entry[1].unlink(missing_ok=True)

    def finish(self) -> None:
        """Close every table and rename it into place (the caller writes ``recordings`` last)."""
        try:
            while self.open:
                name, (writer, temp) = self.open.popitem()
                target = self.dataset.path(name, self.digest)
                try:
                    writer.close()
                    _publish(temp, target)
                except OSError as exc:
                    temp.unlink(missing_ok=True)
                    raise OutputWriteError(
                        f"cannot write {target}: {describe_os_error(exc)}"
                    ) from exc
        finally:
            self.abort()

    def abort(self) -> None:
        """Remove every table not finished (the input failed)."""
        for name in list(self.open):
            with contextlib.suppress(OSError, pa.ArrowException):
                self.discard(name)


def _read(path: Path, columns: list[str] | None = None) -> pa.Table:
    """A file of the dataset (``pq.read_table`` would import pyarrow.dataset, and with it
    pandas when it is installed)."""
    with pq.ParquetFile(path) as handle:
        return handle.read(columns=columns)


def _as(values: pa.ChunkedArray, kind: pa.DataType) -> pa.ChunkedArray:
    """``values`` as ``kind`` (cast only when it is another type: a cast loads
    pyarrow's compute functions)."""
    return values if values.type == kind else values.cast(kind)


def _temp_name(target: Path) -> Path:
    return target.with_name(f"{_PARTIAL}{os.getpid()}-{uuid.uuid4().hex[:8]}-{target.name}")


def _publish(temp: Path, target: Path) -> None:
    with open(temp, "rb+") as handle:
        os.fsync(handle.fileno())
    os.replace(temp, target)
