"""The fleet dataset on disk: one Parquet file per table and input, named by content hash.

``DIR/<table>/<content_hash>.parquet`` holds the rows one input gave that table. Every file
is written under a temporary name and renamed into place (atomic on POSIX), and the
``recordings`` file of an input is written last: an input whose ``recordings`` file exists
is complete, and that set of hashes is the index that makes runs incremental. Files of an
input without its ``recordings`` file (a run killed half way) are removed by the next run.
"""

from __future__ import annotations

import hashlib
import os
import uuid
from collections.abc import Iterable
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from analyzer.errors import UsageError
from analyzer.fleet.columns import RECORDINGS, TABLES
from analyzer.output_file import OutputWriteError, describe_os_error

SUFFIX = ".parquet"
UNREADABLE = "unreadable-"  # key prefix of a file that could not be read (by its path)
_PARTIAL = ".partial-"
HASH_BLOCK = 1 << 20


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
            column = pq.read_table(self.path(RECORDINGS, digest), columns=["error"]).column(0)
        except (OSError, pa.ArrowException):
            return None
        return None if len(column) == 0 else column[0].as_py()

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

    @staticmethod
    def _write_one(target: Path, table: pa.Table) -> None:
        temp = target.with_name(f"{_PARTIAL}{os.getpid()}-{uuid.uuid4().hex[:8]}-{target.name}")
        try:
            pq.write_table(table, temp, compression="zstd")
            with open(temp, "rb+") as handle:
                os.fsync(handle.fileno())
            os.replace(temp, target)
        except OSError as exc:
            temp.unlink(missing_ok=True)
            raise OutputWriteError(f"cannot write {target}: {describe_os_error(exc)}") from exc
