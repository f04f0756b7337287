"""Command line entry point: one sub-command per module in ``analyzer.commands``."""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence
from types import ModuleType

from analyzer import __version__
from analyzer.errors import SourceError, UsageError

# name -> module. Each module has HELP (one line), add_arguments(parser) and
# run(args) -> int, and keeps heavy imports (textual, mcap, can) inside run().
COMMANDS: dict[str, str] = {
    "demo": "analyzer.commands.demo",
    "decode": "analyzer.commands.decode",
    "record": "analyzer.commands.record",
    "convert": "analyzer.commands.convert",
    "info": "analyzer.commands.info",
    "monitor": "analyzer.commands.monitor",
    "simulate": "analyzer.commands.simulate",
    "send": "analyzer.commands.send",
    "commands": "analyzer.commands.list_commands",
    "schemas": "analyzer.commands.schemas",
    "export": "analyzer.commands.export",
}

DESCRIPTION = """\
Protocol analyzer and logger for the gimbal CAN / TCP / UART protocol.

Decode capture files (candump, python-can logs, pcap, raw TCP/UART dumps,
MCAP), capture live from a CAN interface, the IDU's TCP port or a UART,
record MCAP files for Foxglove, and watch everything in a terminal UI.
"""


def _load(name: str) -> ModuleType | None:
    try:
        return importlib.import_module(COMMANDS[name])
    except ModuleNotFoundError as exc:
        if exc.name == COMMANDS[name]:
            return None
        raise


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="gimbal-analyzer",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
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
        p.set_defaults(_module=module)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    module = getattr(args, "_module", None)
    if module is None:
        parser.print_help()
        return 2
    try:
        result: int = module.run(args)
        return result
    except UsageError as exc:
        print(f"gimbal-analyzer {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except SourceError as exc:
        print(f"gimbal-analyzer {args.command}: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # Output piped into `head` and the like: not an error. Point stdout at
        # devnull so the interpreter's final flush does not fail again.
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
