"""`gimbal-analyzer check`: drive a gimbal on the bench through an acceptance sequence, judge it."""

from __future__ import annotations

import argparse
import contextlib
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, TextIO, cast

from analyzer.errors import UsageError

if TYPE_CHECKING:
    from analyzer.capture import Capture
    from analyzer.check.bench_run import BenchRecording
    from analyzer.check.judge import Limits, StepResult
    from analyzer.check.link import CheckLink
    from analyzer.check.observer import Observer
    from analyzer.check.runner import CheckRunner
    from analyzer.check.steps import CheckStep, Options
    from analyzer.mcapio.write.sink import McapSink
    from analyzer.mcapio.write.video import VideoRecorder
    from analyzer.sim.transports import LinkSpec
    from analyzer.timefmt import TimeZone

HELP = "bench acceptance check: drive the gimbal through built-in steps and judge each one"
DESCRIPTION = """\
Drives a gimbal on the bench through a built-in sequence over --to LINK, listens
to its feedback on the same link and judges every step with the same response
analysis as `gimbal-analyzer analyze` (its tolerance, time allowed and yaw
reference), plus the figures measured from the feedback.

  gimbal-analyzer check --to can:socketcan:can0
  gimbal-analyzer check --to tcp:192.168.42.200:2000 --report bench.html
  gimbal-analyzer check --to tcp:127.0.0.1:2000 --steps pitch_angle,pan_speed --json
  gimbal-analyzer check --dry-run                 the frames it would send, nothing sent

The steps, in this order (--steps a,b,c runs a subset, in this order). Each one
first brings the gimbal to its start (the attitude in brackets, with
specified_angle) and waits until the feedback shows it there, so a step does the
same wherever the gimbal was left; a gimbal that cannot get there fails the step,
with the reason:
  feedback      listen a few seconds: feedback period, lost messages, CRC errors
  forward       [pitch -45, yaw motor 150] back to the centre with `forward`
  pitch_angle   [pitch 45] specified_angle pitch -90
  yaw_airframe  [yaw motor 0] specified_angle yaw 150 deg from the nose (DATA4 = 1)
  yaw_geodetic  [yaw motor 0] specified_angle yaw from north: the aircraft's heading
                is taken from the feedback (psi minus the motor's yaw), the target
                is 150 deg of motor travel (the motor at -150 or 150)
  pan_speed     [yaw motor left of the nose] gimbal_control pan at --speed every 50 ms
                for --speed-for, then 0: the turn is centred on the nose
  tilt_speed    [pitch above -25] the same on tilt, downward, centred on -25
  look_down     [pitch 45] look_down: pitch to -90
  zoom          zoom in, stop, zoom 1x: the feedback does not report the zoom, so
                with --video the step is judged from the camera's picture (the scale
                measured, see docs/explanation/camera.md; [pitch -45]), without it
                'skipped'
  tracking      tracking at the image centre (flag on), tracking_stop (flag off)
A move passes when the analysis finds it obeyed and its measured slew rate is at
least --min-slew; a speed step when the rate is within --speed-tolerance of the
speed asked and the gimbal stopped when the commands did. A step the feedback did
not allow to be judged (messages lost or damaged during it) is run again from its
start, 3 times at most, then fails as "no feedback"; a lost message that changes
nothing fails nothing. Each step waits for the gimbal to settle, at most
--time-allowed; to reach its start it has the time a turn at --min-slew takes, and
--time-allowed on top (asked again while it stops short of it and comes nearer).

Safety: without --to nothing is sent (exit 2). Frames go to the one link given and
nowhere else. At the end, on a failure and on Ctrl-C the gimbal is stopped (speeds
0) and then centred (`forward`).

Output: a table as it goes (--json: one JSON object per step). Everything is
recorded to -o FILE.mcap (default check-YYYYMMDD-HHMMSS.mcap, never replacing a
file): the traffic both ways, the decoded events, /analysis/response and the
steps on /check/steps. --report FILE.html writes the flight report of the check
with the steps table on top.

Exit codes: 0 every step passed (or was skipped), 1 a step failed or the link
failed, 2 usage errors (no --to, a bad option), 130 interrupted (gimbal centred).
"""

TO_HELP = (  # check and replay: the bench's one link
    "the gimbal: can:INTERFACE:CHANNEL[@BITRATE], tcp:HOST:PORT (as the ground station "
    "connecting to the IDU) or serial:PORT[@BAUD]; required to send anything"
)
DEFAULT_MIN_SLEW = 30.0
DEFAULT_SPEED_TOLERANCE = 0.25
# What the steps ask for: option, default, unit, what it sets.
STEP_OPTIONS = (
    ("--speed", 20.0, "DPS", "pan / tilt speed of the speed steps, at most 100"),
    ("--speed-for", 2.0, "S", "how long the speed steps turn"),
    ("--listen", 3.0, "S", "how long the feedback step listens"),
)


def _number(low: float, what: str) -> Callable[[str], float]:
    def parse(text: str) -> float:
        try:
            value = (
                float(text[:-1]) / 100 if what == "fraction" and text.endswith("%") else float(text)
            )
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        if not value > low or value != value or value == float("inf"):
            raise argparse.ArgumentTypeError(f"{text!r}: must be above {low:g}")
        return value

    return parse


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from analyzer.commands.analyze import add_settings_arguments

    parser.add_argument("--to", metavar="LINK", help=TO_HELP)
    parser.add_argument(
        "--dry-run", action="store_true", help="print the frames it would send, send nothing"
    )
    parser.add_argument("--steps", metavar="A,B,C", help="run only these steps (see above)")
    parser.add_argument("--json", action="store_true", help="one JSON object per step")
    parser.add_argument(
        "-o",
        "--output",
        metavar="FILE",
        help="the recording (default check-YYYYMMDD-HHMMSS.mcap, never replacing a file)",
    )
    parser.add_argument(
        "-f", "--force", action="store_true", help="replace an existing -o / --report file"
    )
    parser.add_argument("--report", metavar="FILE", help="also write the flight report (HTML)")
    from analyzer.video.spec import add_video_options

    add_video_options(parser)  # the zoom step is judged from the camera's picture
    limits = parser.add_argument_group("pass limits (with --tolerance and --time-allowed)")
    add_settings_arguments(cast(argparse.ArgumentParser, limits))  # a group takes the same
    limits.add_argument(
        "--min-slew",
        type=_number(0.0, "deg/s"),
        default=DEFAULT_MIN_SLEW,
        metavar="DPS",
        help=f"slowest slew rate of a move that passes (default {DEFAULT_MIN_SLEW:g} deg/s)",
    )
    limits.add_argument(
        "--speed-tolerance",
        type=_number(0.0, "fraction"),
        default=DEFAULT_SPEED_TOLERANCE,
        metavar="FRACTION",
        help="how far a measured speed may be off what was asked "
        f"(default {DEFAULT_SPEED_TOLERANCE:g}, i.e. {DEFAULT_SPEED_TOLERANCE * 100:g} %%)",
    )
    steps = parser.add_argument_group("what the steps ask for")
    for flag, default, metavar, words in STEP_OPTIONS:
        steps.add_argument(
            flag,
            type=_number(0.0, metavar),
            default=default,
            metavar=metavar,
            help=f"{words} (default {default:g} {'deg/s' if metavar == 'DPS' else 's'})",
        )


def default_output(now: float | None = None, command: str = "check") -> Path:
    """check-YYYYMMDD-HHMMSS.mcap (``command``-...) in the current directory, with -2, -3
    ... if taken."""
    stamp = time.strftime("%Y%m%d-%H%M%S", time.localtime(now))
    path = Path(f"{command}-{stamp}.mcap")
    number = 2
    while path.exists() or path.is_symlink():
        path = Path(f"{command}-{stamp}-{number}.mcap")
        number += 1
    return path


def run(args: argparse.Namespace) -> int:
    from analyzer.check.judge import Limits
    from analyzer.check.steps import Options, select
    from analyzer.commands.analyze import settings_from

    try:
        steps = select(args.steps)
    except ValueError as exc:
        raise UsageError(f"--steps: {exc}") from None
    if args.speed > 100:
        raise UsageError("--speed: gimbal_control speeds go up to 100 deg/s")
    from analyzer.video.spec import video_specs

    options = Options(args.speed, args.speed_for, args.listen, bool(video_specs(args)))
    limits = Limits(settings_from(args), args.min_slew, args.speed_tolerance)
    if args.dry_run:
        from analyzer.check.dry_run import dry_run_lines

        if args.to is not None:
            from analyzer.sim.transports import parse_link

            parse_link(args.to)  # a wrong link is still an error
        print(
            f"dry run: {len(steps)} step(s); nothing is sent. Commands go on CAN ID 0x00000F01 "
            "(over TCP / UART as the 0x0A frame shown). Times are the latest each frame "
            "would go, for a gimbal that starts centred: a step moves on as soon as the "
            "gimbal has settled."
        )
        for line in dry_run_lines(
            steps, options, limits.settings.time_allowed_s, limits.min_slew_dps
        ):
            print(line)
        return 0
    if args.to is None:
        raise UsageError(
            "give the gimbal's link with --to (can:INTERFACE:CHANNEL, tcp:HOST:PORT or "
            "serial:PORT): the check moves the gimbal and never picks a link itself; "
            "--dry-run shows what it would send"
        )
    return _run_check(args, steps, options, limits)


def _run_check(
    args: argparse.Namespace, steps: tuple[CheckStep, ...], options: Options, limits: Limits
) -> int:
    from analyzer.check.bench_run import BenchRecording, kept_up_to_then
    from analyzer.check.link import CheckLink
    from analyzer.check.observer import Observer
    from analyzer.check.output import JsonPrinter, TablePrinter
    from analyzer.check.runner import CheckRunner
    from analyzer.sim.transports import parse_link

    spec = parse_link(args.to)
    path = _recording_path(args)
    say = sys.stderr if args.json else sys.stdout
    link = CheckLink(spec)
    sink = _recording_sink(args, link, path, spec, options)
    observer = Observer(keep_events=args.report is not None)
    capture, video = _check_capture(args, link, sink, observer, limits)
    printer = JsonPrinter(sys.stdout) if args.json else TablePrinter(sys.stdout)
    runner = CheckRunner(
        link, observer, limits, options, printer, lambda text: print(f"warning: {text}", file=say)
    )
    names = ", ".join(step.name for step in steps)
    print(f"check over {link.description}: {names}; recording {path}", file=say, flush=True)
    if video is not None:
        video.start()
    capture.start()
    if video is not None:  # the zoom step needs pictures from before its first command
        _wait_for_video(video, lambda text: print(f"warning: {text}", file=say))
    _run_steps(runner, steps, BenchRecording(link, observer, capture, sink, path))
    results = runner.results
    _say_how_it_ended(runner, path, say)
    if args.report is not None:
        _write_report(args.report, args.force, observer, results, spec, limits, args.time_zone)
        print(f"report written to {args.report}", file=say)
    if capture.error is not None:
        raise kept_up_to_then(capture.error, path)
    from analyzer.protocol.check_fields import FAIL

    return 1 if any(r.verdict == FAIL for r in results) else 0


def _recording_path(args: argparse.Namespace) -> str:
    """Where the check records (refused before anything moves if it may not be written),
    with the --report page checked as well."""
    from analyzer.output_file import check_output

    if args.output is not None:
        path = check_output(args.output, force=args.force)
    else:
        path = check_output(default_output())
    if args.report is not None:
        check_output(args.report, force=args.force)
    return str(path)


def _recording_sink(
    args: argparse.Namespace, link: CheckLink, path: str, spec: LinkSpec, options: Options
) -> McapSink:
    """The check's recording (the link is closed if it cannot be opened)."""
    from analyzer.check.bench_run import bench_sink
    from analyzer.commands.video_options import video_metadata
    from analyzer.mcapio.write.sink import recording_metadata
    from analyzer.video.spec import VIDEO_HOLD_BACK_S

    metadata = recording_metadata(
        f"check: bench check over {spec}", command="check", **video_metadata(args)
    )
    hold_back = VIDEO_HOLD_BACK_S if options.video else 0.0
    return bench_sink(
        link, path, metadata, force=args.force, hold_back=hold_back, zone=args.time_zone
    )


def _check_capture(
    args: argparse.Namespace, link: CheckLink, sink: McapSink, observer: Observer, limits: Limits
) -> tuple[Capture, VideoRecorder | None]:
    """The capture of the link through the analysis into the recording and the observer,
    and the camera's recorder with --video (its zoom judged from the picture as the
    frames come in)."""
    from analyzer.analysis.stage import Analysis
    from analyzer.capture import Capture
    from analyzer.commands.video_options import video_recorder

    analysis = Analysis(limits.settings)
    video = video_recorder(args, sink)
    if video is not None:
        from analyzer.analysis.camera.live import LiveVideo  # PyAV, OpenCV: --video only

        pictures = LiveVideo([s.spec.name for s in video.streams])
        video.taps.append(pictures.add)
        analysis = Analysis(limits.settings, pictures)
    stages = analysis.stages(before_camera=None if video is None else video.stage)
    sinks = [s for s in (video, sink, observer) if s is not None]
    return Capture(link, sinks, stages=stages), video


def _run_steps(runner: CheckRunner, steps: tuple[CheckStep, ...], bench: BenchRecording) -> None:
    """The steps run; whatever happens, the gimbal is stopped and centred, every verdict
    goes through the pipeline and the recording is finished."""

    def stop_gimbal(completed: bool) -> None:
        if not completed:  # Ctrl-C, a link that failed: stop the gimbal, centre it
            with contextlib.suppress(Exception):
                runner.centre(wait=False)

    def verdicts_seen() -> bool:
        return bench.observer.steps_seen >= len(runner.results)

    with bench.running("the check", stop_gimbal, verdicts_seen):
        runner.run(steps)


def _say_how_it_ended(runner: CheckRunner, path: str, say: TextIO) -> None:
    from analyzer.check.output import summary

    print(summary(runner.results), file=say)
    if runner.centred is False:
        print("warning: the feedback did not show the gimbal back at the centre", file=say)
    elif runner.centred:
        print("the gimbal is stopped and centred", file=say)
    print(f"recorded to {path}", file=say)


VIDEO_WAIT_S = 10.0  # the camera's streams have this long to deliver their first frames


def _wait_for_video(video: VideoRecorder, notice: Callable[[str], None]) -> None:
    """Until every stream delivered a frame (at most VIDEO_WAIT_S); a notice if not."""
    deadline = time.monotonic() + VIDEO_WAIT_S
    while time.monotonic() < deadline:
        if all(stream.frames for stream in video.streams):
            time.sleep(0.5)  # a little picture before the first command
            return
        time.sleep(0.1)
    silent = ", ".join(f"/camera/{s.spec.name}" for s in video.streams if not s.frames)
    notice(f"no picture from {silent} in {VIDEO_WAIT_S:g} s: the zoom step may be unknown")


def _write_report(
    target: str,
    force: bool,
    observer: Observer,
    results: list[StepResult],
    spec: LinkSpec,
    limits: Limits,
    zone: TimeZone,
) -> None:
    from typing import IO

    from analyzer.check.output import steps_table_html
    from analyzer.output_file import OutputFile
    from analyzer.report.collect import ReportData
    from analyzer.report.page import render

    data = ReportData(source=f"check over {spec}", format_name="live")
    for event in observer.events:
        data.add(event)
    settings = limits.settings
    text = render(
        data,
        f"tolerance {settings.tolerance_deg:g} deg, time allowed {settings.time_allowed_s:g} s",
        lead=steps_table_html(results, "Bench check"),
        zone=zone,
    )
    with OutputFile(target, force=force) as out:
        cast("IO[bytes]", out.file).write(text.encode("utf-8"))
