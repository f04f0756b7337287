"""`gimbal-analyzer export`: the protocol tables as a DBC file or a Wireshark dissector."""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path

from analyzer.errors import UsageError

HELP = (
    "export the protocol as a DBC file (cantools, SavvyCAN), a Wireshark Lua dissector or "
    "an ArduPilot Lua mount driver"
)
DESCRIPTION = """\
Write the protocol tables in the form another tool reads, generated from the
same command table that drives decoding:

  dbc        a DBC file: the control frame 0x00000F01 with extended
             multiplexing (S_ID, then CMD, then the control type of
             specified_angle / the mode of snapshot), every parameter with
             scale, unit, range and value labels; the UAV GPS / altitude /
             attitude and text frames; the feedback ID (its 32-byte messages
             span four frames: decode those with gimbal-analyzer).
  wireshark  a Lua dissector for the IDU's TCP link (port 2000, changeable in
             Edit > Preferences > Protocols > GIMBAL): frame types 0x0A, 0x0B,
             0x0C and 0x10, commands and feedback with units and labels,
             CRC checked, frames split over or glued in TCP segments joined.
  ardupilot  an ArduPilot Lua mount driver for the gimbal on CAN (MNT1_TYPE 9,
             a scripting CAN driver): mount targets to gimbal_control /
             specified_angle, the camera library to the camera commands, the
             feedback to the mount's attitude, the UAV status to the gimbal.
             With -o it writes FILE.md beside it: its parameters and set-up.
             Try it first: gimbal-analyzer demo --ardupilot FILE.

examples:
  gimbal-analyzer export dbc -o gimbal.dbc
  gimbal-analyzer export wireshark -o gimbal.lua
  gimbal-analyzer export ardupilot -o mount-viewsheen-driver.lua
  gimbal-analyzer export dbc                     # to standard output
  gimbal-analyzer export dbc -o gimbal.dbc --check      # is my copy stale?

An existing file is replaced only with --force. --check writes nothing and
exits 1 when FILE differs from what the table gives (a stale export).
"""

# format -> (module, function returning the file text, what it is)
FORMATS: dict[str, tuple[str, str, str]] = {
    "dbc": ("analyzer.export.dbc", "dbc_text", "DBC file"),
    "wireshark": ("analyzer.export.wireshark", "lua_text", "Wireshark Lua dissector"),
    "ardupilot": ("analyzer.export.ardupilot", "lua_text", "ArduPilot Lua mount driver"),
}
# format -> (module, function, suffix, what) of the file written beside FILE with -o
COMPANIONS: dict[str, tuple[str, str, str, str]] = {
    "ardupilot": ("analyzer.export.ardupilot", "markdown_text", ".md", "its parameters page"),
}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("format", choices=list(FORMATS), help="what to export")
    parser.add_argument(
        "-o", "--output", metavar="FILE", help="file to write (default: standard output)"
    )
    parser.add_argument("-f", "--force", action="store_true", help="replace FILE if it exists")
    parser.add_argument(
        "--check",
        action="store_true",
        help="write nothing; exit 1 if FILE differs from the export of the current table",
    )


def rendered(name: str) -> str:
    """The text of one export."""
    module, function, _ = FORMATS[name]
    text: str = getattr(importlib.import_module(module), function)()
    return text


def companion(name: str, output: str) -> tuple[Path, str, str] | None:
    """(path, text, what) of the file an export writes beside ``output``, if any."""
    if name not in COMPANIONS:
        return None
    module, function, suffix, what = COMPANIONS[name]
    text: str = getattr(importlib.import_module(module), function)()
    return Path(output).with_suffix(suffix), text, what


def run(args: argparse.Namespace) -> int:
    text = rendered(args.format)
    what = FORMATS[args.format][2]
    if args.check:
        if not args.output:
            raise UsageError("--check needs -o FILE")
        files = [(Path(args.output), text)]
        beside = companion(args.format, args.output)
        if beside is not None:
            files.append(beside[:2])
        stale = [p for p, t in files if not p.is_file() or p.read_text(encoding="utf-8") != t]
        if stale:
            names = ", ".join(str(p) for p in stale)
            print(
                f"{names} out of date (run: gimbal-analyzer export {args.format} "
                f"-o {args.output} --force)"
            )
            return 1
        print(f"{' and '.join(str(p) for p, _ in files)} match the protocol table")
        return 0
    if not args.output or args.output == "-":
        sys.stdout.write(text)
        return 0
    from analyzer.output_file import check_output, write_output

    beside = companion(args.format, args.output)
    if beside is not None:  # refuse before writing anything
        check_output(str(beside[0]), force=args.force)
    write_output(args.output, text, force=args.force)
    print(f"wrote {what} {args.output}", file=sys.stderr)
    if beside is not None:
        path, page, page_what = beside
        write_output(str(path), page, force=args.force)
        print(f"wrote {page_what} {path}", file=sys.stderr)
    return 0
