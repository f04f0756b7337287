"""``gimbal-analyzer report``: a flight report as one self-contained HTML file."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import IO, Any, cast

HELP = "write a flight report: one offline HTML file with plots, findings and diagnostics"

DESCRIPTION = """\
Writes one self-contained HTML file (no network needed to open it, fit to attach
to a support ticket) from any input `decode` reads, recordings included:

  overview       source, time range, counts, verdicts per command
  plots          gimbal pitch / yaw over time with command markers and targets,
                 commanded against measured rates, feedback rate and diagnostics
                 over time, UAV altitude and track (in metres, no map tiles)
  tables         the responses of `gimbal-analyzer analyze` and the diagnostics

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


class EventsInto:
    """A sink handing every decoded event (not findings stored in the input) to ``add``."""

    def __init__(self, add: Callable[[Any], None]) -> None:
        self.add = add

    def handle(self, batch: Any) -> None:
        from analyzer.protocol.types import TOPIC_ANALYSIS_RESPONSE

        add = self.add
        for event in batch.events:
            if event.topic != TOPIC_ANALYSIS_RESPONSE:
                add(event)

    def close(self) -> None:
        pass


def run(args: argparse.Namespace) -> int:
    import sys

    from analyzer.analysis.findings import verdict_line
    from analyzer.analysis.response import ResponseAnalyzer
    from analyzer.commands.analyze import KeepFindings, open_reader, settings_from
    from analyzer.output_file import OutputFile, check_output
    from analyzer.pipeline import Pipeline, run_items
    from analyzer.progress import Progress
    from analyzer.report.collect import ReportData
    from analyzer.report.page import render
    from analyzer.scene.timeline import OverlayTimeline

    inputs = [] if args.file == "-" else [args.file]
    check_output(args.output, force=args.force, inputs=inputs)  # refuse before the work
    settings = settings_from(args)
    reader = open_reader(args)
    analyzer = ResponseAnalyzer(settings)
    data = ReportData(source=reader.source, format_name=reader.format_name)
    kept = KeepFindings(analyzer)
    overlays = OverlayTimeline()  # the camera pictures show what Foxglove draws over them
    # The same decoding and counting as every command; the analyzer is a stage of it.
    pipeline = Pipeline([EventsInto(data.add), EventsInto(overlays.add)], stages=[kept])
    progress = Progress.maybe(reader, sys.stderr, quiet=args.quiet)
    try:
        run_items(reader, pipeline, progress=progress)
    finally:
        reader.close()
    for finding in kept.findings:
        data.add(finding)
    data.notes.extend(reader.notes)
    lead = ""
    data.frames = pipeline.tally.frames
    if reader.format_name == "mcap":  # camera thumbnails of a recording with --video
        from analyzer.check.output import recorded_steps_html
        from analyzer.mcapio.read.video import read_thumbnails

        data.pictures.extend(overlays.pictures(read_thumbnails(args.file)))
        lead = recorded_steps_html(args.file)  # a recording of `check`: its steps on top
    if data.first is not None and data.first == data.last and data.findings:
        data.findings.clear()
        data.notes.append("the input carries no timestamps: responses cannot be timed")
    text = render(
        data,
        f"tolerance {settings.tolerance_deg:g} deg, time allowed {settings.time_allowed_s:g} s",
        lead,
    )
    page = text.encode("utf-8")
    with OutputFile(args.output, force=args.force, inputs=inputs) as out:
        cast("IO[bytes]", out.file).write(page)
    size = len(page)
    print(
        f"wrote {args.output} ({size / 1024:,.0f} KiB): {len(data.findings)} findings "
        f"({verdict_line(data.verdicts())})"
    )
    for note in reader.notes:
        sys.stderr.write(f"note: {note}\n")
    return 0
