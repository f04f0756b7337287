"""Where the per-file tasks run: in this process, a local process pool, or a Dask cluster."""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from pathlib import Path
from typing import TYPE_CHECKING

from analyzer.errors import UsageError
from analyzer.fleet.dataset import Dataset, content_hash, unreadable_hash
from analyzer.fleet.rows import FileRows, FileWork, error_text, file_rows
from analyzer.inputs import EXTENSIONS

if TYPE_CHECKING:
    from distributed import Client

CONNECT_TIMEOUT_S = 30


def walk_inputs(inputs: Sequence[str]) -> list[str]:
    """Files named, and the capture files found under folders named (by extension), sorted.

    URLs (``s3://...``) are taken as they are: the workers read them through fsspec.
    """
    found: list[str] = []
    for name in inputs:
        if "://" in name:
            try:
                import fsspec  # noqa: F401
            except ImportError:
                raise UsageError(
                    f"{name}: reading URLs needs fsspec: pip install 'gimbal-analyzer[cluster]'"
                ) from None
            found.append(name)
        elif os.path.isdir(name):
            for root, dirs, files in os.walk(name):
                dirs[:] = sorted(d for d in dirs if not d.startswith("."))
                for file in sorted(files):
                    if _capture_name(file):
                        found.append(os.path.join(root, file))
        elif os.path.exists(name) or os.path.islink(name):
            found.append(name)
        else:
            raise UsageError(f"no such file or folder: {name}")
    return found


def _capture_name(name: str) -> bool:
    lowered = name.lower()
    if lowered.endswith(".gz"):
        lowered = lowered[:-3]
    return not name.startswith(".") and os.path.splitext(lowered)[1] in EXTENSIONS


def plan(path: str, tags: dict[str, str], **settings: object) -> FileWork:
    """The task of one file: its name, size and content hash (or why it cannot be read)."""
    recording = Path(path.rstrip("/")).name or path
    try:
        digest = content_hash(path)
        size = _size(path)
        error = None
    except OSError as exc:
        digest, size, error = unreadable_hash(path), 0, f"cannot read {path}: {error_text(exc)}"
    return FileWork(
        path=path,
        recording=recording,
        content_hash=digest,
        size_bytes=size,
        tags=tuple(tags.items()),  # in the order given: the first is the report's grouping
        error=error,
        **settings,  # type: ignore[arg-type]
    )


def _size(path: str) -> int:
    if "://" in path:
        import fsspec

        fs, _, paths = fsspec.get_fs_token_paths(path)
        return int(fs.size(paths[0]) or 0)
    return os.path.getsize(path)


def rows_written(work: FileWork, root: str) -> FileRows:
    """A local worker's task: the rows of one file, written into the dataset at ``root``
    by the worker itself (so writing runs in parallel too); the result keeps only counts."""
    result = file_rows(work)
    Dataset(root).write(work.content_hash, result.tables)
    result.row_count = result.rows
    result.tables = {}
    result.written = True
    return result


def run_local(works: Iterable[FileWork], workers: int, root: str) -> Iterator[FileRows]:
    """The tasks in ``workers`` processes (1: in this process), results as they finish."""
    works = list(works)
    if workers <= 1 or len(works) <= 1:
        for work in works:
            yield rows_written(work, root)
        return
    with ProcessPoolExecutor(max_workers=workers) as pool:
        # A few tasks ahead per worker, so no worker waits for the next one.
        pending: set[Future[FileRows]] = set()
        queue = iter(works)
        for work in queue:
            pending.add(pool.submit(rows_written, work, root))
            if len(pending) >= 2 * workers:
                break
        while pending:
            done, pending = wait(pending, return_when=FIRST_COMPLETED)
            for future in done:
                yield future.result()
                nxt = next(queue, None)
                if nxt is not None:
                    pending.add(pool.submit(rows_written, nxt, root))


def run_dask(works: Iterable[FileWork], address: str) -> Iterator[FileRows]:
    """The same tasks on a Dask cluster (``dask.distributed``); results as they finish."""
    client = connect(address)
    try:
        from distributed import as_completed

        works = list(works)
        keys = [f"fleet-rows-{hashlib.sha256(repr(w).encode()).hexdigest()[:24]}" for w in works]
        futures = client.map(file_rows, works, key=keys)
        with client.as_current():
            for future in as_completed(futures):
                yield future.result()
    finally:
        client.close()


def connect(address: str) -> Client:
    """A Dask client of the scheduler at ``address``; UsageError when it is not reachable."""
    try:
        from distributed import Client
    except ImportError:
        raise UsageError(
            "--dask needs dask.distributed: pip install 'gimbal-analyzer[cluster]'"
        ) from None
    try:
        client: Client = Client(address, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
    except (OSError, TimeoutError) as exc:
        raise UsageError(f"cannot reach the Dask scheduler at {address}: {exc}") from None
    return client
