"""``gimbal-analyzer table``: many inputs into one Parquet dataset, one table per kind."""

from __future__ import annotations

import argparse
import os
import re
import shutil
import sys
import time
from collections import Counter
from dataclasses import replace
from typing import TYPE_CHECKING

from analyzer.errors import EXIT_FAILED, UsageError

if TYPE_CHECKING:
    from distributed import Client

    from analyzer.fleet.dataset import Dataset
    from analyzer.fleet.rows import FileWork

HELP = "add recordings and capture files to a fleet dataset (Parquet, one table per kind)"

DESCRIPTION = """\
Decodes and analyses every input exactly as `decode`, `info` and `analyze` do
(folders are walked for capture files and recordings) and adds the rows to a
Parquet dataset in DIR, one folder per table:

  recordings     one row per input: its tags, source, format, start and end
                 (UTC), frames, feedback messages, CRC errors and rate, gaps,
                 diagnostics by kind, findings by verdict, content hash, error
  commands, attitude, ranging, uav_gps, uav_altitude, uav_attitude,
  uav_text, diagnostics
                 every decoded event, typed from the command table and layouts
  findings       every finding of the response analysis (`analyze`)

An input whose content is already in DIR is skipped, so a nightly job adds only
new flights. Every file is written under a temporary name and renamed: a killed
run leaves whole files only, and the next run removes what it left unfinished.
A damaged or unreadable input becomes a row with its error; the rest goes on.

  gimbal-analyzer table flights/ -o fleet --tag gimbal=G-104 --tag aircraft=A7
  gimbal-analyzer table new/*.mcap -o fleet --workers 2
  gimbal-analyzer table /shared/flights -o fleet --dask tcp://scheduler:8786

--workers N runs N processes (default: the cores). --dask sends the same
per-file tasks to an existing Dask cluster (pip install 'gimbal-analyzer[cluster]');
its workers read the inputs by the same path or URL (shared storage, s3://...)
and write their Parquet files into DIR themselves, which they must reach by the
same path (checked first); this process writes each input's recordings row last.
--client-writes is for a DIR the workers cannot reach: they send the rows back and
this process writes them. A wrong address stops before DIR is made.

An input that could not be read at all (keyed by its path) or failed to decode
is a row too, with its error; the next runs skip it and say it failed before.
--retry-failed decodes every input whose row has an error again; a file
unreadable before is taken by itself once it reads. A run in which every input
it had to add failed exits with code 1.

Rows are written as they are decoded, a Parquet row group at a time: memory
does not grow with the length of a flight.

Tags stay with the content: an input already in DIR keeps its tags (a warning
when this run gives others); --retag gives it this run's tags.

  gimbal-analyzer table flights/ -o fleet --dask tcp://scheduler:8786 --client-writes
  gimbal-analyzer table flights/ -o fleet --retry-failed

Ask the dataset with `gimbal-analyzer fleet DIR`.
"""

_TAG = re.compile(r"^[a-z][a-z0-9_]{0,62}$")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from analyzer.commands.analyze import add_settings_arguments
    from analyzer.inputs import FORMATS

    parser.add_argument("inputs", nargs="+", metavar="INPUT", help="files or folders")
    parser.add_argument("-o", "--output", required=True, metavar="DIR", help="dataset folder")
    parser.add_argument(
        "--tag",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a column of the recordings table with this value for these inputs (repeatable)",
    )
    parser.add_argument(
        "--workers",
        type=int,
        default=os.cpu_count() or 1,
        metavar="N",
        help="local processes (default: the cores, here %(default)s)",
    )
    parser.add_argument(
        "--dask", metavar="ADDRESS", help="run the tasks on this Dask scheduler (tcp://HOST:8786)"
    )
    parser.add_argument(
        "--client-writes",
        action="store_true",
        help="with --dask: the workers send every row here and this process writes DIR "
        "(when the workers cannot reach DIR)",
    )
    parser.add_argument(
        "--retry-failed",
        action="store_true",
        help="decode again the inputs whose row has an error (unreadable or failed before)",
    )
    parser.add_argument(
        "--retag",
        action="store_true",
        help="inputs already in DIR take the --tag values of this run (default: kept, "
        "with a warning when they differ)",
    )
    parser.add_argument(
        "--format", metavar="FORMAT", help="read every input as " + "/".join(FORMATS)
    )
    parser.add_argument(
        "--port", type=int, default=2000, help="TCP port of the IDU in pcap captures (default 2000)"
    )
    add_settings_arguments(parser)
    parser.add_argument("-q", "--quiet", action="store_true", help="only the closing summary")


def parse_tags(values: list[str]) -> dict[str, str]:
    """``KEY=VALUE`` options -> a dict; UsageError for a bad or reserved key."""
    from analyzer.fleet.columns import recordings_schema

    reserved = set(recordings_schema([]).names)
    tags: dict[str, str] = {}
    for value in values:
        key, sep, text = value.partition("=")
        key = key.strip()
        if not sep or not _TAG.match(key):
            raise UsageError(
                f"--tag {value!r}: give KEY=VALUE, KEY in lower case letters, digits and _"
            )
        if key in reserved:
            raise UsageError(f"--tag {key}: that name is a column of the recordings table")
        tags[key] = text
    return tags


def run(args: argparse.Namespace) -> int:
    from analyzer.extras import FLEET, require
    from analyzer.input_options import check_port

    require(FLEET, "`table`", uses=("pyarrow",))
    from analyzer.fleet.runner import connect, walk_inputs

    tags = parse_tags(args.tag)
    if args.workers < 1:
        raise UsageError(f"--workers must be 1 or more, not {args.workers}")
    check_port(args.port)
    if args.client_writes and not args.dask:
        raise UsageError("--client-writes goes with --dask")
    started = time.monotonic()
    paths = walk_inputs(args.inputs)
    if not args.dask:
        return _run(args, paths, tags, started, None)
    # The cluster first: a wrong address leaves nothing behind. Its workers have other
    # working folders: they get absolute paths.
    paths = [p if "://" in p else os.path.abspath(p) for p in paths]
    client = connect(args.dask)
    try:
        return _run(args, paths, tags, started, client)
    finally:
        client.close()


def _open_dataset(args: argparse.Namespace, client: Client | None) -> Dataset:
    """The dataset folder, made if new; with Dask workers that write, checked to be one
    they reach (a new folder goes again when they do not)."""
    from analyzer.fleet.dataset import Dataset
    from analyzer.fleet.runner import workers_reach

    dataset = Dataset(args.output)
    made = not dataset.root.exists()
    dataset.create()
    if client is not None and not args.client_writes:
        try:
            workers_reach(client, os.path.abspath(args.output))
        except UsageError:
            if made:
                shutil.rmtree(dataset.root, ignore_errors=True)  # empty folders made above
            raise
    return dataset


def _run(
    args: argparse.Namespace,
    paths: list[str],
    tags: dict[str, str],
    started: float,
    client: Client | None,
) -> int:
    from analyzer.fleet.runner import run_dask, run_local

    dataset = _open_dataset(args, client)
    root = os.path.abspath(args.output)
    out = sys.stdout
    removed = dataset.remove_partial()
    if removed:
        out.write(f"removed {removed} unfinished file(s) of an interrupted run in {args.output}\n")
    todo, skipped, failed_before = _plan(args, paths, tags, dataset)
    if not args.quiet and client is None and (args.workers <= 1 or len(todo) <= 1):
        todo = [replace(work, progress=True) for work in todo]  # read here: a progress line
    out.flush()
    if client is None:  # local workers write their files themselves
        results = run_local(todo, args.workers, args.output)
    else:  # Dask workers too, but for the recordings rows (with --client-writes: every row)
        results = run_dask(todo, client, None if args.client_writes else root)
    added = rows = errors = 0
    where: Counter[str] = Counter()
    for n, result in enumerate(results, 1):
        if not result.written:
            dataset.write(result.work.content_hash, result.tables)
        where[result.worker] += 1
        if result.error is not None:
            errors += 1
            line = f"error {result.work.path}: {result.error}"
        else:
            added += 1
            rows += result.rows
            line = f"added {result.work.path}: {result.rows:,} rows ({result.seconds:.2f} s)"
        if not args.quiet:
            out.write(f"[{n}/{len(todo)}] {line}\n")
            out.flush()
    seconds = time.monotonic() - started
    again = f" ({failed_before} had failed: --retry-failed tries again)" if failed_before else ""
    out.write(
        f"{args.output}: {len(paths)} input(s), {added} added ({rows:,} rows), "
        f"{skipped} skipped (content already there){again}, {errors} with errors; "
        f"{seconds:.1f} s\n"
    )
    if client is not None:
        runners = ", ".join(f"{name} ({count})" for name, count in sorted(where.items()))
        out.write(f"tasks ran on: {runners or 'none'}\n")
        writer = "this process" if args.client_writes else "the workers (recordings rows: here)"
        out.write(f"written by: {writer}\n")
    if todo and errors == len(todo):
        out.flush()
        sys.stderr.write(
            f"gimbal-analyzer table: error: every input to add failed ({errors}); "
            "their rows say why\n"
        )
        return EXIT_FAILED
    return 0


def _plan(
    args: argparse.Namespace, paths: list[str], tags: dict[str, str], dataset: Dataset
) -> tuple[list[FileWork], int, int]:
    """The inputs to do (new content, or a failure to retry); how many skipped, and how
    many of those had failed."""
    from analyzer.fleet.dataset import unreadable_hash
    from analyzer.fleet.runner import plan

    settings = {
        "fmt": args.format,
        "port": args.port,
        "tolerance_deg": args.tolerance,
        "time_allowed_s": args.time_allowed,
        "flag_allowed_s": args.flag_allowed,
    }
    out = sys.stdout
    todo: list[FileWork] = []
    seen: dict[str, str] = {}
    skipped = failed_before = 0
    for path in paths:
        work = plan(path, tags, **settings)
        digest = work.content_hash
        if work.error is None and dataset.holds(stale := unreadable_hash(path)):
            dataset.forget(stale)  # unreadable before, readable now: its error row goes
        if digest in seen:
            skipped += 1
            if not args.quiet:
                out.write(f"skipped {path}: same content as {seen[digest]}\n")
            continue
        seen[digest] = path
        if dataset.holds(digest):
            failure = dataset.failure(digest)
            if failure is not None and args.retry_failed:
                dataset.forget(digest)
                if not args.quiet:
                    out.write(f"retrying {path}: it failed before ({failure})\n")
                todo.append(work)
                continue
            skipped += 1
            why = f"already in {args.output}"
            if failure is not None:
                failed_before += 1
                why = f"failed before ({failure}); --retry-failed tries again"
            if not args.quiet:
                out.write(f"skipped {path}: {why}\n")
            _check_tags(args, path, dataset, digest, tags)
            continue
        todo.append(work)
    return todo, skipped, failed_before


def _check_tags(
    args: argparse.Namespace, path: str, dataset: Dataset, digest: str, tags: dict[str, str]
) -> None:
    """Content already in the dataset under other tags: replaced with --retag, else a warning."""
    stored = dataset.tags(digest)
    if stored is None or stored == tags or not (tags or args.retag):
        return
    was = _tag_text(stored)
    if args.retag:
        dataset.retag(digest, tags)
        if not args.quiet:
            sys.stdout.write(f"retagged {path}: {_tag_text(tags)} (was {was})\n")
        return
    sys.stderr.write(
        f"gimbal-analyzer table: warning: {path} is in {args.output} with the tags {was}, "
        f"not {_tag_text(tags)}: kept; --retag replaces them\n"
    )


def _tag_text(tags: dict[str, str]) -> str:
    return " ".join(f"{k}={v}" for k, v in tags.items()) or "(none)"
