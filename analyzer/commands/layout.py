"""`gimbal-analyzer layout`: write the ready Foxglove Studio layout for recordings."""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path

from analyzer.errors import SourceError, UsageError

HELP = "write a Foxglove Studio layout (map, log, plots, modes, commands, diagnostics)"
DEFAULT_OUTPUT = "gimbal-layout.json"
DESCRIPTION = f"""\
Write a Foxglove Studio layout for gimbal-analyzer recordings:

  Map                UAV track (/uav/gps/fix) and laser-ranging target (/gimbal/ranging/fix)
  Log                diagnostics (/diagnostics/log)
  Plot               gimbal pitch and yaw with the commanded pan / tilt speeds
  State Transitions  control mode, tracking and command names over time
  Indicator          tracking on / off
  Raw Messages       /gimbal/command
  Table              /diagnostics

Import it once in Foxglove: Layouts (left sidebar) -> Import layout, and pick
the file; it then applies to every recording you open.

  gimbal-analyzer layout                       writes {DEFAULT_OUTPUT}
  gimbal-analyzer layout -o ~/gimbal.json
  gimbal-analyzer layout -o -                  to standard output

An existing file is replaced only with --force.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "-o",
        "--output",
        default=DEFAULT_OUTPUT,
        metavar="FILE",
        help=f"file to write (default {DEFAULT_OUTPUT}; '-' for standard output)",
    )
    parser.add_argument("-f", "--force", action="store_true", help="replace FILE if it exists")


def rendered() -> str:
    from analyzer.mcapio.layout import layout

    return json.dumps(layout(), indent=2) + "\n"


def run(args: argparse.Namespace) -> int:
    text = rendered()
    if args.output == "-":
        sys.stdout.write(text)
        return 0
    _write(Path(args.output), text, force=args.force)
    print(
        f"wrote {args.output}: in Foxglove, Layouts -> Import layout, then open a recording",
        file=sys.stderr,
    )
    return 0


def _write(path: Path, text: str, *, force: bool) -> None:
    """Write through a temporary file and an atomic rename; never replace without --force."""
    if path.is_symlink():
        raise UsageError(f"{path} is a symbolic link; give the real path")
    if path.is_dir():
        raise UsageError(f"{path} is a directory")
    if path.exists() and not force:
        raise UsageError(f"{path} exists; add --force to replace it")
    directory = path.parent if str(path.parent) else Path(".")
    if not directory.is_dir():
        raise UsageError(f"directory {directory} does not exist")
    try:
        fd, temp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=directory)
    except OSError as exc:
        raise UsageError(f"cannot write {path}: {exc.strerror}") from None
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as out:
            out.write(text)
        os.chmod(temp, 0o644)
        os.replace(temp, path)
    except OSError as exc:
        os.unlink(temp)
        raise SourceError(f"cannot write {path}: {exc.strerror}") from None
