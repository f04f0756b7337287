"""`gimbal-analyzer replay FLIGHT --to LINK`: a flight's commands sent to a gimbal on the bench."""

from __future__ import annotations

import argparse
import contextlib
import sys
from typing import TYPE_CHECKING, Any

from analyzer.errors import SourceError, UsageError
from analyzer.input_options import add_input_arguments

if TYPE_CHECKING:
    from analyzer.replay.flight import Span
    from analyzer.replay.player import Outcome
    from analyzer.sim.transports import LinkSpec

HELP = "send a flight's commands and UAV status to a gimbal on the bench, with the flight's timing"
DESCRIPTION = """\
Reproduces a flight on the bench: sends what the ground station sent in FLIGHT
(anything `decode` reads: a recording, candump, pcap, a DataFlash log, ...) to the
gimbal on --to LINK, each frame at its time in the flight to the millisecond, and
records the bench session as `record` does. Then `compare FLIGHT BENCH.mcap` says
whether the gimbal on the bench did what it did in flight.

  gimbal-analyzer replay flight.mcap --to tcp:192.168.42.200:2000 -o bench.mcap
  gimbal-analyzer replay flight.log --to can:socketcan:can0 --start 60 --end 120
  gimbal-analyzer replay flight.log --dry-run          the frames and their times, nothing sent

What is sent: the commands (/gimbal/command, both components) and the UAV status
(GPS, altitude, attitude, text), with the bytes the flight carried. Never the
gimbal's own feedback. The frames go in the framing of the link given, whatever
the flight was: a CAN flight replays to the IDU over TCP (0x0A and 0x0B frames),
a TCP flight to a CAN bus (the commands on 0x00000F01, the status on its IDs).

Before the first frame the gimbal is brought to the attitude the flight began with
(its pitch and yaw motor angle in the flight's feedback when the span begins) and
waited for (--no-align: replay from wherever it is). The recording (-o, default
replay-YYYYMMDD-HHMMSS.mcap, never replacing a file) holds the traffic both ways,
the decoded events and /analysis/response; its metadata names the flight and the
span, and two link diagnostics mark where the replayed span begins and ends.

Safety, as in `check`: without --to nothing is sent (exit 2). Frames go to the one
link given. A frame with a value outside the document's ranges, or a command the
document does not have, is refused: not sent, and listed before the replay begins.
At the end, on Ctrl-C and on a failure the gimbal gets speeds 0 and then `forward`.
A gimbal whose feedback stops for 3 s (or never starts) stops the replay.

Exit codes: 0 the span was replayed, 1 the gimbal went silent, could not be
aligned or the link failed, 2 usage errors (no --to, a flight without commands,
an empty span), 130 interrupted (gimbal centred).
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from analyzer.commands.analyze import positive_number
    from analyzer.commands.check import TO_HELP
    from analyzer.commands.simulate import seconds_value

    add_input_arguments(parser)
    parser.add_argument("--to", metavar="LINK", help=TO_HELP)
    parser.add_argument(
        "-o",
        "--output",
        metavar="FILE",
        help="the bench recording (default replay-YYYYMMDD-HHMMSS.mcap, never replacing a file)",
    )
    parser.add_argument("-f", "--force", action="store_true", help="replace an existing -o file")
    parser.add_argument(
        "--speed",
        type=positive_number,
        default=1.0,
        metavar="X",
        help="replay at X times the flight's speed (default 1: its own timing)",
    )
    parser.add_argument(
        "--start",
        type=seconds_value,
        default=0.0,
        metavar="S",
        help="begin S seconds into the flight",
    )
    parser.add_argument(
        "--end",
        type=seconds_value,
        metavar="S",
        help="end S seconds into the flight (default: its end)",
    )
    parser.add_argument(
        "--no-align",
        action="store_true",
        help="do not bring the gimbal to the flight's first attitude first",
    )
    parser.add_argument(
        "--dry-run", action="store_true", help="print the frames and their times, send nothing"
    )
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress line")


def run(args: argparse.Namespace) -> int:
    from analyzer.commands.check import default_output
    from analyzer.commands.input_pass import read_through
    from analyzer.output_file import check_output
    from analyzer.replay.dry_run import dry_run_lines, plan_lines
    from analyzer.replay.flight import FlightError, FlightReader, span_of
    from analyzer.sim.transports import parse_link

    if args.end is not None and args.end <= args.start:
        raise UsageError(f"--end {args.end:g} must be after --start {args.start:g}")
    spec = parse_link(args.to) if args.to is not None else None
    if spec is None and not args.dry_run:
        raise UsageError(
            "give the gimbal's link with --to (can:INTERFACE:CHANNEL, tcp:HOST:PORT or "
            "serial:PORT): the replay moves the gimbal and never picks a link itself; "
            "--dry-run shows what it would send"
        )
    path = None
    if not args.dry_run:
        inputs = [] if args.file == "-" else [args.file]
        chosen = args.output if args.output is not None else default_output(command="replay")
        path = check_output(chosen, force=args.force, inputs=inputs)
    reader = FlightReader()
    read_through(args.file, [reader], file_format=args.format, port=args.port, quiet=args.quiet)
    try:
        span = span_of(reader, args.file, args.start, args.end)
    except FlightError as exc:
        raise UsageError(str(exc)) from None
    for line in plan_lines(span, args.speed):
        print(line)
    if path is None:
        print("dry run: nothing is sent; the times are after the alignment, at --speed")
        for line in dry_run_lines(span, args.speed, not args.no_align, spec):
            print(line)
        return 0
    assert spec is not None
    return _replay(args, span, spec, str(path))


def _replay(args: argparse.Namespace, span: Span, spec: LinkSpec, path: str) -> int:
    from analyzer.analysis.stage import Analysis
    from analyzer.capture import Capture
    from analyzer.check.bench_run import BenchRecording, bench_sink, kept_up_to_then
    from analyzer.check.link import CheckLink
    from analyzer.check.observer import Observer
    from analyzer.mcapio.write.sink import recording_metadata
    from analyzer.replay.player import Player

    link = CheckLink(spec, purpose="the replay")
    metadata = recording_metadata(
        f"replay: {args.file} over {spec}",
        command="replay",
        flight=args.file,
        flight_span=f"{span.start_s:.3f}-{span.end_s:.3f} s",
        speed=f"{args.speed:g}",
        aligned="no" if args.no_align else "yes",
    )
    sink = bench_sink(link, path, metadata, force=args.force, zone=args.time_zone)
    observer = Observer()
    capture = Capture(link, [sink, observer], stages=Analysis().stages())
    progress = None if args.quiet else _progress(span, args.speed)
    player = Player(link, observer, source=link.source_name, progress=progress)
    print(f"replay over {link.description}; recording {path}", flush=True)
    if not args.no_align and span.attitude is None:
        print("the flight has no attitude feedback: the gimbal is not aligned first")

    def stop_gimbal(completed: bool) -> None:
        _clear_progress(progress)
        if not completed:  # Ctrl-C, a link that failed: stop the gimbal, centre it
            player.close_span("interrupted")
            with contextlib.suppress(Exception):
                player.centre(wait=False)
        else:
            with contextlib.suppress(SourceError):
                player.centre(wait=True)

    capture.start()
    with BenchRecording(link, observer, capture, sink, path).running("the replay", stop_gimbal):
        outcome = player.play(span, speed=args.speed, align=not args.no_align)
    for line in _summary(outcome, span, path):
        print(line)
    if capture.error is not None:
        raise kept_up_to_then(capture.error, path)
    if outcome.stopped:
        print(f"gimbal-analyzer replay: {outcome.stopped}", file=sys.stderr)
        return 1
    return 0


def _summary(outcome: Outcome, span: Span, path: str) -> list[str]:
    lines = []
    arrival = outcome.arrival
    if arrival is not None and arrival.sent:
        lines.append(f"aligned to the flight's first attitude in {arrival.took_s:.1f} s")
    elif arrival is not None:
        lines.append("the gimbal was at the flight's first attitude already")
    if outcome.began is not None:
        took = (outcome.ended or outcome.began) - outcome.began
        status = outcome.sent - outcome.commands
        frames = f"{outcome.commands:,} commands" + (f", {status:,} UAV status" if status else "")
        lines.append(
            f"sent {outcome.sent:,} of {len(span.frames):,} frames ({frames}) in {took:.1f} s"
        )
        if outcome.late_s:
            late = sorted(outcome.late_s)
            median = late[len(late) // 2] * 1000
            lines.append(
                f"each went {median:.2f} ms after its time in the flight (median), "
                f"the latest {outcome.latest_s * 1000:.2f} ms"
            )
    if outcome.centred is False:
        lines.append("warning: the feedback did not show the gimbal back at the centre")
    elif outcome.centred:
        lines.append("the gimbal is stopped and centred")
    lines.append(f"recorded to {path}")
    return lines


def _progress(span: Span, speed: float) -> Any:
    from analyzer.progress import isatty

    if not isatty(sys.stderr):
        return None
    total = (span.end - span.start) / speed

    def show(outcome: Outcome, elapsed: float) -> None:
        sys.stderr.write(
            f"\r  replaying: {elapsed:6.1f} of {total:.1f} s, {outcome.sent:,} frames sent "
        )
        sys.stderr.flush()

    return show


def _clear_progress(progress: Any) -> None:
    if progress is not None:
        sys.stderr.write("\r\033[K")
        sys.stderr.flush()
