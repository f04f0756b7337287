"""Where the per-file tasks run: in this process, a local process pool, or a Dask cluster."""

from __future__ import annotations

import hashlib
import multiprocessing
import os
import socket
import uuid
from collections.abc import Iterable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from pathlib import Path
from typing import TYPE_CHECKING

from analyzer.errors import SourceError, UsageError
from analyzer.fleet.columns import RECORDINGS
from analyzer.fleet.dataset import Dataset, content_hash, unreadable_hash
from analyzer.fleet.rows import FileRows, FileWork, error_text, file_rows
from analyzer.inputs import EXTENSIONS
from analyzer.output_file import describe_os_error

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


def rows_written(work: FileWork, root: str, index_here: bool = False) -> FileRows:
    """A worker's task: the rows of one file, written into the dataset at ``root`` by the
    worker itself (so writing runs in parallel too); the result keeps only counts.

    ``index_here``: the worker writes every table but ``recordings`` and sends that row
    back, for the caller to write last (a Dask worker on another machine: the input is
    complete in the index only once the caller has its row).
    """
    dataset = Dataset(root)
    out = dataset.stream(work.content_hash)
    try:
        result = file_rows(work, out)
        if result.error is None:
            out.finish()  # every table in place before the input's recordings row
    finally:
        out.abort()
    index = result.tables.pop(RECORDINGS)
    if index_here:
        result.tables = {RECORDINGS: index}
    else:
        dataset.write(work.content_hash, {RECORDINGS: index})
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
    # Not fork: this process has threads by now (pyarrow's, DuckDB's, the progress line's),
    # and a child forked from them may deadlock on a lock one of them held (Python 3.12
    # warns of it). A fork server starts clean workers, as Python 3.14 does by default.
    methods = multiprocessing.get_all_start_methods()
    context = multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")
    with ProcessPoolExecutor(max_workers=workers, mp_context=context) as pool:
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


def run_dask(works: Iterable[FileWork], client: Client, root: str | None) -> Iterator[FileRows]:
    """The same tasks on a Dask cluster (``dask.distributed``); results as they finish.

    With ``root`` (a path the workers reach) the workers write their tables there and send
    back the ``recordings`` row; without, they send every row back to be written here.
    """
    from distributed import as_completed

    works = list(works)
    keys = [f"fleet-rows-{hashlib.sha256(repr(w).encode()).hexdigest()[:24]}" for w in works]
    if root is None:
        futures = client.map(file_rows, works, key=keys)
    else:
        futures = client.map(rows_written, works, root=root, index_here=True, key=keys)
    with client.as_current():
        for future in as_completed(futures):
            try:
                result = future.result()
            except Exception as exc:  # a task's failure, or a cluster without the package
                raise cluster_error(client, exc) from None
            yield result


def cluster_error(client: Client, exc: BaseException) -> SourceError:
    """A failure on the cluster as one line: the task's error, or what the cluster lacks."""
    address = getattr(client.scheduler, "address", "?")
    chain = f"{exc} {exc.__cause__ or ''}"
    if "No module named 'analyzer'" in chain:
        return SourceError(
            f"the Dask cluster at {address} cannot run gimbal-analyzer's tasks: install the "
            "package where its scheduler and workers run (pip install 'gimbal-analyzer[cluster]')"
        )
    return SourceError(f"the Dask cluster at {address} failed: {error_text(exc)}")


def workers_reach(client: Client, root: str) -> None:
    """UsageError unless every worker of the cluster can read and write ``root`` (the same
    folder as here: a probe file written here must be there)."""
    try:
        client.wait_for_workers(1, timeout=CONNECT_TIMEOUT_S)
    except TimeoutError:
        waited = f"waited {CONNECT_TIMEOUT_S} s"
        raise UsageError(f"the Dask cluster has no workers ({waited})") from None
    token = uuid.uuid4().hex
    probe = Dataset(root).scratch(f"reach-{token}")
    probe.write_text(token, encoding="utf-8")
    try:
        seen: dict[str, str] = client.run(sees, str(probe), token)
    finally:
        probe.unlink(missing_ok=True)
    blind = sorted(f"{worker} ({why})" for worker, why in seen.items() if why)
    if blind:
        raise UsageError(
            f"the Dask workers cannot write {root} (it must be the same folder for them, "
            f"e.g. shared storage): {', '.join(blind)}; give --client-writes to have them "
            "send the rows here instead"
        )


def sees(probe: str, token: str) -> str:
    """On a worker: why it cannot use the folder of ``probe`` ("" when it can)."""
    try:
        with open(probe, encoding="utf-8") as handle:
            if handle.read() != token:
                return "another folder at that path"
        mine = f"{probe}-{os.getpid()}"
        with open(mine, "w", encoding="utf-8") as handle:
            handle.write(token)
        os.unlink(mine)
    except OSError as exc:
        return describe_os_error(exc)
    return ""


def connect(address: str) -> Client:
    """A Dask client of the scheduler at ``address``; UsageError when it is not reachable."""
    try:
        from distributed import Client
    except ImportError:
        raise UsageError(
            "--dask needs dask.distributed: pip install 'gimbal-analyzer[cluster]'"
        ) from None
    _probe(address)
    try:
        client: Client = Client(address, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
    except (OSError, TimeoutError) as exc:
        raise UsageError(f"cannot reach the Dask scheduler at {address}: {exc}") from None
    return client


def _probe(address: str) -> None:
    """UsageError at once when nothing listens at a ``tcp://HOST:PORT`` address (Dask's
    client would retry a refused connection until its timeout)."""
    scheme, sep, rest = address.partition("://")
    if (sep and scheme != "tcp") or (not rest and sep):
        return
    host, _, port = (rest if sep else address).rpartition(":")
    if not host or not port.isdigit():
        return
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=CONNECT_TIMEOUT_S):
            pass
    except ConnectionRefusedError:
        raise UsageError(
            f"cannot reach the Dask scheduler at {address}: connection refused "
            "(is the scheduler running, on that port?)"
        ) from None
    except OSError:
        return  # a slow or unknown network: the client's own timeout decides
