"""``gimbal-analyzer analyze``: did the gimbal do what it was told? One finding per command."""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING, Any

from analyzer.input_options import add_input_arguments, check_port
from analyzer.terminal_text import printable

if TYPE_CHECKING:
    from analyzer.api.reading import Decoding

HELP = "did the gimbal obey? compare each command with the attitude feedback that followed"

DESCRIPTION = """\
The protocol has no acknowledgements: the only way to know whether the gimbal
did what the ground station asked is to compare each command with the attitude
feedback that follows (every 500 ms). For every command with a visible effect
this prints a finding: obeyed, partial, not_obeyed, or unknown when the
feedback does not allow a judgement.

  specified_angle, look_down, forward   time to reach the target within the
        tolerance, overshoot, final error, or what happened instead (never moved,
        moved the other way, stopped short, still on its way). Yaw errors are the
        shortest way round (-180..180]. A yaw target is judged in the frame the
        command named: on the motor yaw (from the nose) when DATA4 = 1; else on
        psi (from north) when the flight controller's attitude (0x0000FF13) is
        present or psi is offset from the motor yaw (the gimbal knows its
        heading); with neither, on the motor yaw in a CAN capture and on psi in
        a TCP/UART one (which cannot show FF13). Each finding says which
        (yaw_reference) and why (reference_reason).
  gimbal_control   measured pan/tilt rate against the commanded speed (ratio,
        lag), still moving after the commands stopped, and commands repeated more
        slowly than the 50 ms the document recommends.
  tracking, tracking_stop   the feedback's tracking flag: it must change within
        --flag-allowed (three feedback periods, 1.5 s); staying as it was through
        that is not_obeyed, also when the next command follows. A tracking_stop when
        the flag was not on has nothing to obey: unknown ("tracking was never on").
  limits           pitch -110 / +60, yaw motor +-170 (+-325 on 3.5x models).
  feedback         messages per second, gaps, CRC errors, per minute, and each
        gap: a silence of 1.5 feedback periods (0.75 s) or more lost
        round(silence / 0.5 s) - 1 messages, the same count decode --summary,
        info and table give. The text says these in health words (healthy,
        DEGRADED, LOST) and counts them apart from the commands' verdicts.

Findings are written in time order as they are decided; the analysis keeps
only the feedback a pending judgement can still need, so long flights take
time in proportion and memory that does not grow. A progress line shows on a
terminal (-q: none).

It reads every input `decode` reads (candump, python-can logs, pcap, raw
TCP/UART dumps, MCAP recordings).

examples:
  gimbal-analyzer analyze samples/flight-candump.log
  gimbal-analyzer analyze demo.mcap --problems
  gimbal-analyzer analyze flight.log --tolerance 2 --time-allowed 8
  gimbal-analyzer analyze flight.log --json | jq 'select(.verdict != "obeyed")'

Times are UTC. With --json each finding is one JSON object (schema:
schemas/analysis.response.schema.json), 'time' being the command's time.
"""


def positive_number(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not value > 0 or value != value or value == float("inf"):
        raise argparse.ArgumentTypeError(f"{text!r}: must be a number above 0")
    return value


def add_settings_arguments(parser: argparse.ArgumentParser) -> None:
    from analyzer.analysis.settings import (
        DEFAULT_FLAG_ALLOWED_S,
        DEFAULT_TIME_ALLOWED_S,
        DEFAULT_TOLERANCE_DEG,
        FLAG_PERIODS,
    )

    parser.add_argument(
        "--tolerance",
        type=positive_number,
        default=DEFAULT_TOLERANCE_DEG,
        metavar="DEG",
        help="an angle this close to the target counts as reached "
        f"(default {DEFAULT_TOLERANCE_DEG:g} deg)",
    )
    parser.add_argument(
        "--time-allowed",
        type=positive_number,
        default=DEFAULT_TIME_ALLOWED_S,
        metavar="S",
        help="seconds a target command (specified_angle, look_down, forward) has to reach "
        f"its angle (default {DEFAULT_TIME_ALLOWED_S:g} s)",
    )
    parser.add_argument(
        "--flag-allowed",
        type=positive_number,
        default=DEFAULT_FLAG_ALLOWED_S,
        metavar="S",
        help="seconds tracking / tracking_stop have to show in the feedback's tracking flag "
        f"(default {DEFAULT_FLAG_ALLOWED_S:g} s: {FLAG_PERIODS} feedback periods)",
    )


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_input_arguments(parser)
    add_settings_arguments(parser)
    parser.add_argument(
        "--json", action="store_true", help="one JSON object per finding (JSON lines)"
    )
    parser.add_argument(
        "--problems", action="store_true", help="only findings that are not 'obeyed'"
    )
    parser.add_argument(
        "-q", "--quiet", action="store_true", help="no progress line while a file is read"
    )


def open_decoding_of(args: argparse.Namespace) -> Decoding:
    """The input of ``analyze`` and ``report``: read and decoded as ``decode`` and the
    Python API's ``read`` and ``analyze`` read and decode it."""
    from analyzer.api.reading import open_decoding

    check_port(args.port)
    return open_decoding(args.file, args.format, port=args.port)


def settings_from(args: argparse.Namespace) -> Any:
    from analyzer.analysis.response import Settings

    return Settings(
        tolerance_deg=args.tolerance,
        time_allowed_s=args.time_allowed,
        flag_allowed_s=args.flag_allowed,
    )


def run(args: argparse.Namespace) -> int:
    from analyzer.analysis.stage import Analysis
    from analyzer.commands.analyze_output import FindingsOutput
    from analyzer.pipeline import run_reader
    from analyzer.progress import Progress

    settings = settings_from(args)
    decoding = open_decoding_of(args)
    reader, pipeline = decoding.reader, decoding.pipeline
    analysis = Analysis.of_file(args.file, settings)
    judging = analysis.judging()
    out = sys.stdout
    output = FindingsOutput(
        judging, pipeline.tally, json_lines=args.json, problems=args.problems, zone=args.time_zone
    ).to(out)
    pipeline.stages.append(output.stage)  # the analysis, whose findings it writes
    pipeline.sinks.append(output)
    # The text report is written at the end: the terminal is free for a progress line.
    progress = Progress.maybe(reader, sys.stderr, out, not args.json, quiet=args.quiet)
    run_reader(reader, pipeline, batch_items=decoding.batch_items, progress=progress)
    # The camera not judged: the video extra is missing.
    notes = [*reader.notes, *([analysis.camera_note] if analysis.camera_note else [])]
    if output.untimed:
        # A raw byte dump has no clock: "0.0 s later" everywhere would be nonsense.
        notes.append(
            f"{args.file} carries no timestamps (a raw TCP/UART byte dump?), so responses "
            "cannot be timed; record with `gimbal-analyzer record` to get times"
        )
    if not args.json:
        commands = pipeline.tally.topics.get("/gimbal/command", 0)
        header = (
            f"response analysis of {args.file} ({reader.format_name}): {commands:,} commands; "
            f"tolerance {settings.tolerance_deg:g} deg, time allowed {settings.time_allowed_s:g} s"
        )
        output.finish(header)
    out.flush()
    for note in notes:
        sys.stderr.write(f"note: {printable(note)}\n")
    return 0
