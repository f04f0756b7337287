"""``gimbal-analyzer report``: a flight report as one self-contained HTML file."""

from __future__ import annotations

import argparse
from typing import IO, TYPE_CHECKING, cast

if TYPE_CHECKING:
    from analyzer.report.camera import PictureChoice
    from analyzer.report.collect import ReportData
    from analyzer.report.stream import EventsInto
    from analyzer.scene.timeline import OverlayTimeline

HELP = "write a flight report: one offline HTML file with plots, findings and diagnostics"

DESCRIPTION = """\
Writes one self-contained HTML file (no network needed to open it, fit to attach
to a support ticket) from any input `decode` reads, recordings included:

  overview       source, time range, counts, verdicts
  plots          gimbal pitch / yaw over time with a mark for every command and the
                 targets, commanded against measured rates, feedback rate and
                 diagnostics over time, UAV altitude and track (in metres, equal
                 scale, no map tiles); drag across a time plot to zoom in
  tables         the findings of `gimbal-analyzer analyze` counted per command and
                 check, with the worst examples; the flight controller's status
                 texts; the diagnostics; pictures of a recording's camera before
                 each command not obeyed and at its verdict

The file stays small for any length of flight: plots keep each time bucket's
lowest and highest samples, findings are counted (every one is in `analyze
--json` and in a recording's /analysis/response).

  gimbal-analyzer report flight.log -o report.html
  gimbal-analyzer report demo.mcap -o demo-report.html --tolerance 2

The plots are drawn by Chart.js (MIT), inlined into the file. An existing output
file is replaced only with --force, and never one of the inputs.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from analyzer.commands.analyze import add_settings_arguments
    from analyzer.input_options import add_input_arguments

    add_input_arguments(parser)
    parser.add_argument(
        "-o",
        "--output",
        default="report.html",
        metavar="FILE",
        help="the HTML file to write (default report.html)",
    )
    parser.add_argument(
        "-f", "--force", action="store_true", help="replace the output file if it exists"
    )
    parser.add_argument(
        "-q", "--quiet", action="store_true", help="no progress line while the file is read"
    )
    add_settings_arguments(parser)


def run(args: argparse.Namespace) -> int:
    import sys

    from analyzer.analysis.stage import NOT_JUDGED, Analysis, WithCamera
    from analyzer.commands.analyze import open_decoding_of, settings_from
    from analyzer.extras import VIDEO
    from analyzer.output_file import OutputFile, check_output
    from analyzer.pipeline import run_reader
    from analyzer.progress import Progress
    from analyzer.report.collect import ReportData
    from analyzer.report.page import render
    from analyzer.report.stream import EventsInto, FindingsInto

    inputs = [] if args.file == "-" else [args.file]
    check_output(args.output, force=args.force, inputs=inputs)  # refuse before the work
    settings = settings_from(args)
    decoding = open_decoding_of(args)
    reader, pipeline = decoding.reader, decoding.pipeline
    data = ReportData(source=reader.source, format_name=reader.format_name)
    left_out: list[str] = []  # what the missing video extra leaves out, in words
    # A recording with video: camera commands judged by it.
    recording = args.file if reader.format_name == "mcap" else None
    analysis = Analysis.of_file(recording, settings, keep_pictures=True)
    analysis.tell(lambda _: left_out.append(NOT_JUDGED))
    judging = analysis.judging()
    camera_stage = judging.camera if isinstance(judging, WithCamera) else None
    sinks = [EventsInto(data.add)]
    overlays = _overlays(args, sinks, left_out) if recording is not None else None
    camera_notes = [f"{' and '.join(left_out)}: {VIDEO.missing}"] if left_out else []
    # The same decoding and counting as every command; the analysis is a stage of it.
    pipeline.sinks.extend(sinks)
    pipeline.stages.append(FindingsInto(judging, data))
    progress = Progress.maybe(reader, sys.stderr, quiet=args.quiet)
    run_reader(reader, pipeline, progress=progress)
    data.notes.extend([*reader.notes, *camera_notes])
    data.frames = pipeline.tally.frames
    _mark_untimed(data)
    pictures, lead = _pictures(args, data, overlays)
    judged = ""
    if camera_stage is not None and not data.untimed:
        from analyzer.report.camera_judged import judged_section

        judged = judged_section(camera_stage.judged, camera_stage.pictures, args.time_zone)
    text = render(
        data,
        f"tolerance {settings.tolerance_deg:g} deg, time allowed {settings.time_allowed_s:g} s",
        pictures,
        lead,
        judged,
        args.time_zone,
    )
    page = text.encode("utf-8")
    with OutputFile(args.output, force=args.force, inputs=inputs) as out:
        cast("IO[bytes]", out.file).write(page)
    size = len(page)
    print(
        f"wrote {args.output} ({size / 1024:,.0f} KiB): {data.findings.total:,} findings "
        f"(verdicts: {data.counts.verdict_line()}; feedback: {data.counts.health_line()})"
    )
    for note in [*reader.notes, *camera_notes]:
        sys.stderr.write(f"note: {note}\n")
    return 0


def _overlays(
    args: argparse.Namespace, sinks: list[EventsInto], left_out: list[str]
) -> OverlayTimeline:
    """A recording's camera pictures show what Foxglove draws over them: the overlay at
    each picture's moment, kept as the events go by (a sink added to ``sinks``), not the
    overlay of every feedback."""
    import sys

    from analyzer.extras import VIDEO, installed
    from analyzer.mcapio.read.video import thumbnail_times
    from analyzer.progress import further_pass
    from analyzer.report.stream import EventsInto
    from analyzer.scene.timeline import OverlayTimeline

    with further_pass(args.file, sys.stderr, quiet=args.quiet, label="camera times ") as read:
        overlays = OverlayTimeline(thumbnail_times(args.file, read))
    if overlays.moments:
        sinks.append(EventsInto(overlays.add))
        if not installed(VIDEO):
            left_out.append("camera pictures shown without their overlay")
    return overlays


def _mark_untimed(data: ReportData) -> None:
    """A raw byte dump has no clock: "0.0 s later" everywhere would be nonsense, so its
    findings are dropped, and a note says why."""
    from analyzer.report.tables import UNTIMED

    if data.first is not None and data.first == data.last and data.topics.total() > 1:
        data.untimed = True
        if data.findings.total or data.commands:
            data.drop_findings()
            data.notes.append(UNTIMED)


def _pictures(
    args: argparse.Namespace, data: ReportData, overlays: OverlayTimeline | None
) -> tuple[PictureChoice | None, str]:
    """The camera pictures chosen for the page and, for a recording of `check`, its
    steps on top (none of either for a file that is no recording)."""
    import sys

    if overlays is None or data.first is None or data.last is None:
        return None, ""
    from analyzer.check.output import recorded_steps_html
    from analyzer.mcapio.read.video import read_thumbnails  # camera pictures
    from analyzer.progress import further_pass
    from analyzer.report import camera

    shown = camera.shown_findings(data.findings.worst_first())
    with further_pass(args.file, sys.stderr, quiet=args.quiet, label="pictures ") as read:
        thumbnails = overlays.pictures(read_thumbnails(args.file, read))
        pictures = camera.choose(thumbnails, data.first, data.last, shown)
    lead = recorded_steps_html(args.file)  # a recording of `check`: its steps on top
    return (pictures if pictures.count else None), lead
