"""``python -m fuzz``: fuzz one target or several, list them, or replay inputs."""

from __future__ import annotations

import argparse
import faulthandler
import subprocess
import sys
import time
import traceback
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from fuzz.engine import REPO
from fuzz.figures import Figures, finds, parse, table
from fuzz.rules import HANG_S
from fuzz.targets import ALL, Target, of_all, targets

WORK = REPO / "build" / "fuzz"
TAIL_LINES = 60  # of a run's log shown when it found something
EPILOG = f"""\
examples:
  python -m fuzz --list                    the targets
  python -m fuzz blf --seconds 300         fuzz one target for five minutes
  python -m fuzz all --seconds 60          every target at once
  python -m fuzz all --seconds 40 --table  the same, its figures only (CI does this)
  python -m fuzz blf asc --seconds 120 --jobs 2
                                           several, one process each, and a table
  python -m fuzz blf --replay FILE...      run inputs once (a crash to reproduce)

A crash is any exception from the library but ValueError / FileNotFoundError, a
command that does not end with exit 0 or one 'error:' line and exit 2, an input
taking more than {HANG_S:.0f} s, or more than 1 GB of memory. What is found is saved in
build/fuzz/TARGET/ (crash-*, timeout-*, oom-*); fix it and copy the input to
fuzz/regressions/TARGET/, where the test suite runs it.
"""


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m fuzz",
        description="Coverage-guided fuzzing (atheris, libFuzzer) of every input.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("targets", nargs="*", metavar="TARGET", help="what to fuzz (see --list)")
    p.add_argument("--list", action="store_true", help="list the targets")
    p.add_argument("--seconds", type=float, default=60.0, help="per target (default 60)")
    p.add_argument("--runs", type=int, help="stop after this many inputs")
    p.add_argument("--jobs", type=int, default=1, help="targets fuzzed at once (default 1)")
    p.add_argument("--work", type=Path, help="corpus and findings (default build/fuzz/TARGET)")
    p.add_argument(
        "--table", action="store_true", help="run in a subprocess and print only its figures"
    )
    p.add_argument("--markdown", action="store_true", help="the figures as a Markdown table")
    p.add_argument("--replay", nargs="+", type=Path, metavar="FILE", help="run these inputs")
    return p


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    known = targets()
    if args.list or not args.targets:
        for name, target in known.items():
            print(f"{name:12} {target.what}")
        return 0
    unknown = [name for name in args.targets if name not in known]
    if unknown:
        parser().error(f"unknown target(s) {', '.join(unknown)}; valid: {', '.join(known)}")
    if args.replay:
        if len(args.targets) != 1:
            parser().error("--replay takes one target")
        return replay(known[args.targets[0]], args.replay)
    if len(args.targets) == 1 and args.jobs == 1 and not (args.table or args.markdown):
        from fuzz.engine import fuzz

        name = args.targets[0]
        fuzz(known[name], args.seconds, args.work or WORK / name, args.runs)
        return 0  # libFuzzer exits the process itself
    return several(args.targets, args.seconds, args.runs, args.jobs, args.markdown)


def replay(target: Target, paths: list[Path]) -> int:
    """Each input once; a traceback for those that crash, and how long each took."""
    failed = 0
    for path in paths:
        data = path.read_bytes()
        name = target.name
        if name == ALL and data:
            name = of_all(data)[0].name
        faulthandler.dump_traceback_later(HANG_S * 6, exit=True)
        start = time.monotonic()
        try:
            target.run(data)
            verdict = "ok"
        except Exception:
            verdict = "CRASH\n" + traceback.format_exc()
        finally:
            faulthandler.cancel_dump_traceback_later()
        took = time.monotonic() - start
        if took > HANG_S and verdict == "ok":
            verdict = f"HANG (more than {HANG_S:.0f} s)"
        failed += verdict != "ok"
        print(f"{path} ({name}, {len(data):,} bytes, {took:.3f} s): {verdict}")
    return 1 if failed else 0


def several(names: list[str], seconds: float, runs: int | None, jobs: int, md: bool) -> int:
    """Each target in a process of its own, ``jobs`` at a time; their figures as a table."""

    def one(name: str) -> Figures:
        work = WORK / name
        work.mkdir(parents=True, exist_ok=True)
        command = [sys.executable, "-m", "fuzz", name, "--seconds", str(seconds)]
        command += ["--runs", str(runs)] if runs is not None else []
        log = work / "log.txt"
        before = set(finds(work))
        with log.open("w", encoding="utf-8") as out:
            done = subprocess.run(command, cwd=REPO, stdout=out, stderr=subprocess.STDOUT)
        figures = parse(name, log.read_text(encoding="utf-8", errors="replace"))
        figures.found = sorted(set(finds(work)) - before)
        figures.exit_code = done.returncode
        print(f"{name}: {figures.executions:,} inputs, {len(figures.found)} found", flush=True)
        return figures

    with ThreadPoolExecutor(max(1, jobs)) as pool:
        runs_done = list(pool.map(one, names))
    print(table(runs_done, markdown=md))
    found = [f"build/fuzz/{f.target}/{name}" for f in runs_done for name in f.found]
    for figures in runs_done:
        if not figures.ok:  # what the run said: the traceback, where the input is
            log = (WORK / figures.target / "log.txt").read_text(encoding="utf-8", errors="replace")
            print(f"-- {figures.target} (exit {figures.exit_code}):", flush=True)
            print(*log.splitlines()[-TAIL_LINES:], sep="\n")
    if found:
        print("found (reproduce with python -m fuzz TARGET --replay FILE):", *found, sep="\n  ")
    return 0 if all(figures.ok for figures in runs_done) else 1


if __name__ == "__main__":
    sys.exit(main())
