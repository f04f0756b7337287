"""`gimbal-analyzer monitor`: watch a live source, or replay a file, in the terminal UI."""

from __future__ import annotations

import argparse
import sys

from analyzer.errors import SourceError, UsageError
from analyzer.live.options import add_foxglove_options

HELP = "watch a live source (or replay a capture file) in a terminal UI"
DESCRIPTION = """\
Show the gimbal's state, the UAV status, a log of decoded commands, a bus sniffer
table of every CAN ID and the diagnostics, live. Nothing is ever transmitted: CAN
interfaces are opened passive, the TCP proxy forwards bytes unchanged.

  gimbal-analyzer monitor --source can:socketcan:can0
  gimbal-analyzer monitor --source tcp:192.168.42.200:2000
  gimbal-analyzer monitor --source 'proxy:0.0.0.0:2000->192.168.42.200:2000'
  gimbal-analyzer monitor --source serial:/dev/ttyUSB0@115200
  gimbal-analyzer monitor --source file:flight.log               replay at recorded speed
  gimbal-analyzer monitor --source file:flight.log --speed 10    ten times faster
  gimbal-analyzer monitor --source file:flight.log --speed max   as fast as it reads

Keys: q quit, p pause, f filter, / search, c clear counters, r raw bytes,
v all topics, enter event details, ? help. To record at the same time use
`gimbal-analyzer record --source ... -o flight.mcap --tui`. With --foxglove the
same stream is served live to Foxglove too (ws://127.0.0.1:8765).
"""


def parse_speed(text: str) -> float | None:
    """'max' -> None (as fast as possible), else a positive multiple of recorded speed."""
    if text.lower() in ("max", "fast", "0"):
        return None
    try:
        value = float(text)
    except ValueError:
        raise UsageError(f"--speed takes a number or 'max', not {text!r}") from None
    if not value > 0:
        raise UsageError(f"--speed must be positive, not {text}")
    return value


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--source",
        required=True,
        metavar="SPEC",
        help="can:INTERFACE:CHANNEL[@BITRATE], tcp:HOST:PORT, proxy:LISTEN->IDU, "
        "serial:DEVICE[@BAUD] or file:PATH",
    )
    parser.add_argument(
        "--speed",
        default=None,
        metavar="X",
        help="file sources: replay speed as a multiple of recorded speed (default 1), "
        "or 'max' for as fast as possible",
    )
    add_foxglove_options(parser)


def run(args: argparse.Namespace) -> int:
    from analyzer.sources import open_source, parse_source
    from analyzer.sources.spec import FileSpec

    spec = parse_source(args.source)
    is_file = isinstance(spec, FileSpec)
    if args.speed is not None and not is_file:
        raise UsageError("--speed applies to file: sources only")
    speed = parse_speed(args.speed) if args.speed is not None else (1.0 if is_file else None)
    if not (sys.stdin.isatty() and sys.stdout.isatty()):
        raise UsageError("monitor needs a terminal; use `decode` to print events to a pipe")

    from analyzer.analysis.stage import Analysis
    from analyzer.capture import Capture
    from analyzer.live.attach import foxglove_status, start_foxglove, with_foxglove
    from analyzer.tui.app import run_app

    live = start_foxglove(args, encode=True)  # no recording to feed it
    source = open_source(args.source, replay_speed=speed)
    capture = Capture(source, [] if live is None else [live], stages=Analysis().stages())
    label = str(getattr(source, "description", args.source))
    result = run_app(
        capture,
        source_label=with_foxglove(label, live),
        live_status=foxglove_status(live),
        zone=args.time_zone,
    )
    if capture.error is not None:
        raise capture.error  # a SourceError: one line, exit 1
    stats = capture.stats
    if result == 0 and not is_file and not (stats.frames or stats.chunks):
        raise SourceError(f"nothing was received from {label} in {stats.elapsed_s:.1f} s")
    return int(result)
