"""What counts as a crash: the library's and the command line's rules for bad input."""

from __future__ import annotations

import io
import sys
from collections.abc import Callable, Sequence
from contextlib import redirect_stderr, redirect_stdout
from typing import TypeVar

T = TypeVar("T")

# The only exceptions the library documents for input it cannot read (read, analyze,
# Recording): anything else escaping is a crash.
DOCUMENTED = (ValueError, FileNotFoundError)
HANG_S = 5.0  # one input of a few kB taking longer than this is a hang
MEMORY_MB = 1024  # a process growing past this is a crash (libFuzzer's -rss_limit_mb)
EXIT_USAGE = 2  # the command line's exit code for an input it cannot read


class Crash(AssertionError):
    """An input broke a rule without raising by itself (a bad exit, a garbled error)."""


def library(call: Callable[[], T]) -> T | None:
    """``call()``, or None when it raised a documented error; anything else goes on."""
    try:
        return call()
    except DOCUMENTED:
        return None


def one_error_line(command: str, code: int, err: str) -> bool:
    """The command line's way with bad input: exit 0 with only notes on stderr (each a
    ``note:`` line), or exit 2 with one ``error:`` line (and the indented details some
    errors list, e.g. what a file holds instead). Never a traceback."""
    lines = err.splitlines()
    if "Traceback" in err or "Exception ignored" in err:
        return False
    if code == 0:
        return all(line.startswith(("note: ", "  ")) for line in lines)
    head = f"gimbal-analyzer {command}: error: "
    return (
        code == EXIT_USAGE
        and bool(lines)
        and lines[0].startswith(head)
        and all(line.startswith("  ") for line in lines[1:])
    )


def run_cli(args: Sequence[str], stdin: bytes = b"") -> tuple[int, str, str]:
    """``gimbal-analyzer ARGS`` in this process: (exit code, stdout, stderr)."""
    from analyzer.cli import main

    out, err = io.StringIO(), io.StringIO()
    saved = sys.stdin
    sys.stdin = io.TextIOWrapper(io.BytesIO(stdin), encoding="utf-8")
    try:
        with redirect_stdout(out), redirect_stderr(err):
            try:
                code = main(list(args))
            except SystemExit as exc:  # argparse's usage errors (it printed the line)
                code = exc.code if isinstance(exc.code, int) else EXIT_USAGE
    finally:
        sys.stdin = saved
    return code, out.getvalue(), err.getvalue()


def cli(args: Sequence[str]) -> int:
    """``gimbal-analyzer ARGS``; a Crash unless it kept the command line's rules."""
    code, _, err = run_cli(args)
    if not one_error_line(args[0], code, err):
        raise Crash(f"gimbal-analyzer {' '.join(args)}: exit {code}, stderr:\n{err[-3000:]}")
    return code
