"""Command line entry point: one sub-command per module in ``analyzer.commands``."""

from __future__ import annotations

import argparse
import importlib
import os
import re
import sys
from collections.abc import Sequence
from types import ModuleType
from typing import NoReturn

from analyzer import timefmt
from analyzer.errors import (
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_USAGE,
    OutputError,
    SourceError,
    UsageError,
    exit_code_table,
)
from analyzer.stdio import (
    guarded_stdout,
    interrupt_name,
    sigterm_as_interrupt,
    silence_stdout,
    utf8_when_redirected,
)
from analyzer.terminal_text import printable
from analyzer.version import __version__

# name -> module. Each module has HELP (one line), add_arguments(parser) and
# run(args) -> int, and keeps heavy imports (textual, mcap, can) inside run().
COMMANDS: dict[str, str] = {
    "demo": "analyzer.commands.demo",
    "decode": "analyzer.commands.decode",
    "analyze": "analyzer.commands.analyze",
    "report": "analyzer.commands.report",
    "record": "analyzer.commands.record",
    "convert": "analyzer.commands.convert",
    "info": "analyzer.commands.info",
    "monitor": "analyzer.commands.monitor",
    "simulate": "analyzer.commands.simulate",
    "send": "analyzer.commands.send",
    "check": "analyzer.commands.check",
    "replay": "analyzer.commands.replay",
    "compare": "analyzer.commands.compare",
    "interfaces": "analyzer.commands.interfaces",
    "commands": "analyzer.commands.list_commands",
    "schemas": "analyzer.commands.schemas",
    "layout": "analyzer.commands.layout",
    "export": "analyzer.commands.export",
    "table": "analyzer.commands.table",
    "fleet": "analyzer.commands.fleet",
}

DESCRIPTION = """\
Protocol analyzer and logger for the gimbal CAN / TCP / UART protocol.

Decode capture files (candump, python-can logs, pcap, raw TCP/UART dumps,
MCAP), capture live from a CAN interface, the IDU's TCP port or a UART,
record MCAP files for Foxglove, and watch everything in a terminal UI.
"""


class OneLineParser(argparse.ArgumentParser):
    """argparse with its errors in one line and a hint, instead of the usage block; an
    unknown option is reported by the command it was given to."""

    commands: dict[str, argparse.ArgumentParser]
    given: Sequence[str] = ()  # the command line, for hints

    def parse_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> argparse.Namespace:
        for command in getattr(self, "commands", {}).values():
            if isinstance(command, OneLineParser):
                command.given = list(sys.argv[1:] if args is None else args)
        parsed, extra = self.parse_known_args(args, namespace)
        if extra:
            named = getattr(self, "commands", {}).get(getattr(parsed, "command", None) or "")
            (named or self).error(f"unrecognized arguments: {' '.join(extra)}")
        return parsed

    def error(self, message: str) -> NoReturn:
        hint = f"see: {self.prog} --help"
        if re.search(r"(^|\s)-f\b", message) and "--format" in self.format_help():
            hint = f"-f is --force wherever it exists; the format is --format FORMAT; {hint}"
        if re.search(r"required: .*--source\b", message):
            hint = f"{source_hint(self.given)}; {hint}"
        self.exit(EXIT_USAGE, f"{self.prog}: error: {printable(message)} ({hint})\n")


def source_hint(given: Sequence[str]) -> str:
    """What to say when --source is missing: a file given without it is replayed as
    ``--source file:PATH``."""
    paths = [a for a in given[1:] if not a.startswith("-") and os.path.isfile(a)]
    if paths:
        return f"a file is replayed with --source file:{paths[0]}"
    return "a file is replayed with --source file:PATH"


def _load(name: str) -> ModuleType | None:
    try:
        return importlib.import_module(COMMANDS[name])
    except ModuleNotFoundError as exc:
        if exc.name == COMMANDS[name]:
            return None
        raise


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The parser of every command, or (``only``) of that one alone: running a command
    imports no other command's module, which keeps start-up short."""
    parser = OneLineParser(
        prog="gimbal-analyzer",
        description=DESCRIPTION,
        epilog="exit codes (the same for every command):\n" + exit_code_table(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    parser.add_argument("--local-time", action="store_true", help=timefmt.FLAG_HELP)
    # UTC unless main() reads --local-time: a namespace parsed here alone has a zone too
    parser.set_defaults(time_zone=timefmt.UTC)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    parser.commands = {}
    for name in [only] if only in COMMANDS else COMMANDS:
        module = _load(name)
        if module is None:
            continue
        help_text: str = getattr(module, "HELP", "")
        p = sub.add_parser(
            name,
            help=help_text,
            description=getattr(module, "DESCRIPTION", help_text),
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        module.add_arguments(p)
        parser.commands[name] = p
        # Also after the command name; SUPPRESS keeps a value given before it.
        p.add_argument(
            "--local-time", action="store_true", default=argparse.SUPPRESS, help=timefmt.FLAG_HELP
        )
        p.set_defaults(_module=module)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run one command; every failure ends as one line on stderr and an exit code from
    the table in ``analyzer.errors`` (no tracebacks for the user's mistakes or the OS's)."""
    utf8_when_redirected(sys.stdout, sys.stderr)
    # numpy's OpenBLAS starts a thread per core when numpy is imported; no command does
    # matrix algebra big enough to gain from them, and starting them costs every run.
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    # pyarrow's buffers from glibc's malloc (tuned below) rather than its own mimalloc, read
    # when pyarrow is imported: mimalloc keeps about 20 MB of pages the Parquet writer of
    # `table` used once, and takes no less CPU time.
    os.environ.setdefault("ARROW_DEFAULT_MEMORY_POOL", "system")
    keep_freed_memory()
    with guarded_stdout(), sigterm_as_interrupt():
        name = "gimbal-analyzer"
        try:
            parser = build_parser(_command_name(sys.argv[1:] if argv is None else argv))
            try:
                args = parser.parse_args(argv)
            except SystemExit:  # --help, --version, a usage error: argparse printed it
                sys.stdout.flush()
                raise
            if args.command:
                name = f"gimbal-analyzer {args.command}"
            result = _run(parser, args, name)
            sys.stdout.flush()
            return result
        except OutputError as exc:
            print(f"{name}: error: {printable(str(exc))}", file=sys.stderr)
            silence_stdout()
            return EXIT_FAILED
        except BrokenPipeError:
            # Output piped into `head` and the like: not an error.
            silence_stdout()
            return EXIT_OK
        except KeyboardInterrupt as exc:
            print(f"{name}: interrupted ({interrupt_name(exc)})", file=sys.stderr)
            return EXIT_INTERRUPTED


def _command_name(argv: Sequence[str]) -> str | None:
    """The command named on the command line (the options before it take no value)."""
    for arg in argv:
        if not arg.startswith("-"):
            return arg
        if arg == "--":
            return None
    return None


def _run(parser: argparse.ArgumentParser, args: argparse.Namespace, name: str) -> int:
    module = getattr(args, "_module", None)
    # Built once here and passed down to what shows times to people (no global switch).
    args.time_zone = timefmt.chosen_zone(bool(getattr(args, "local_time", False)))
    if module is None:
        parser.print_help()
        return EXIT_USAGE
    try:
        result: int = module.run(args)
        return result
    except UsageError as exc:
        print(f"{name}: error: {printable(str(exc))}", file=sys.stderr)
        for line in getattr(exc, "details", ()):
            print(f"  {printable(line)}", file=sys.stderr)
        return EXIT_USAGE
    except SourceError as exc:
        print(f"{name}: error: {printable(str(exc))}", file=sys.stderr)
        return EXIT_FAILED


def keep_freed_memory() -> None:
    """Ask glibc's malloc to keep memory a block of work freed for the next block.

    Files are read a block (1 MiB) at a time, and each block's text and arrays are freed
    before the next is read. By default glibc hands large freed areas back to the system
    and the next block takes them again, page by page: a quarter of the CPU time of
    decoding a dense log went to those page faults. Blocks of up to 8 MiB now come from
    the heap, and up to 64 MiB of free heap is kept (the peak memory does not change).
    Elsewhere than glibc, nothing is done."""
    if not sys.platform.startswith("linux"):
        return
    import ctypes

    try:
        libc = ctypes.CDLL("libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):  # another C library (musl): its own way
        return
    mallopt(_M_TRIM_THRESHOLD, 64 << 20)
    mallopt(_M_MMAP_THRESHOLD, 8 << 20)


_M_TRIM_THRESHOLD = -1  # glibc's malloc.h
_M_MMAP_THRESHOLD = -3
