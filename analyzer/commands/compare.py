"""`gimbal-analyzer compare A B`: did the gimbal behave the same in two recordings?"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

from analyzer.errors import UsageError

if TYPE_CHECKING:
    from analyzer.analysis.response import Settings
    from analyzer.compare.judged import Judged

HELP = "did the gimbal behave the same in two recordings? judged commands side by side"
DESCRIPTION = """\
Judges two recordings (anything `decode` reads) with the response analysis of
`analyze` and pairs what was judged by kind and order: the n-th stick movement of
A with the n-th of B, and so for commands sent once, re-sent targets, the stops
after a stick, tracking sessions, camera commands (judged from a recording's
video) and limits reached. Two recordings of `check` are compared step by step.
Each pair shows both verdicts and both sets of figures (ratios, lag, response,
slew, settle, latency, overshoot, error, scale) and whether the gimbal behaved
differently, and why:

  a different verdict, or one side without the other;
  a ratio, slew or rate of B outside 75-133 % of A's (the band of an obeyed rate;
      a check's rate: its --speed-tolerance band, 25 %);
  a time read from the feedback (response, settle, latency) more than one
      feedback period (0.5 s) apart: the feedback only tells time to that;
  a lag more than 0.25 s apart (the lag the analysis says);
  an angle (overshoot, error, movement after a stop) more than --tolerance apart;
  a zoom's scale more than 10 % apart; lost feedback or CRC errors not the same.

A recording `replay` made is compared over the span it replayed (what came before,
the gimbal brought to the flight's first attitude, and after, is left out), and
the flight it replayed over that same span; times count from the span's start.

  gimbal-analyzer compare flight.mcap bench.mcap
  gimbal-analyzer compare bench-fw1.mcap bench-fw2.mcap --html fw.html
  gimbal-analyzer compare check-old.mcap check-new.mcap --json | jq 'select(.differs)'

--json prints one object per pair (command, kind, check, time_a and time_b in Unix
seconds, at_a and at_b in seconds on the table's time axis, verdict_a, verdict_b,
each figure as NAME_a and NAME_b, differs, why), then {"summary": {...}}.
--html FILE draws both attitude tracks on one time axis, with the pairs below.

Exit codes: 0 nothing differs, 1 something differs, 2 usage errors (an input that
cannot be read, a bad option).
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from analyzer.commands.analyze import add_settings_arguments
    from analyzer.input_options import add_port_argument

    parser.add_argument("a", metavar="A", help="the first recording or capture file")
    parser.add_argument("b", metavar="B", help="the second, compared with the first")
    parser.add_argument("--json", action="store_true", help="one JSON object per pair")
    parser.add_argument("--html", metavar="FILE", help="also write the comparison as HTML")
    parser.add_argument(
        "-f", "--force", action="store_true", help="replace an existing --html file"
    )
    add_port_argument(parser)
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress line")
    add_settings_arguments(parser)


def run(args: argparse.Namespace) -> int:
    from analyzer.commands.analyze import settings_from
    from analyzer.compare.figures import rules
    from analyzer.compare.output import json_lines, table
    from analyzer.compare.pairs import pair_items
    from analyzer.output_file import check_output

    if args.html is not None:
        check_output(args.html, force=args.force, inputs=[args.a, args.b])
    settings = settings_from(args)
    a = judge(args.a, settings, args.port, quiet=args.quiet or args.json)
    b = judge(args.b, settings, args.port, quiet=args.quiet or args.json)
    figure_rules = rules(settings.tolerance_deg)
    pairs = pair_items(a.items(b), b.items(a), figure_rules)
    if args.json:
        json_lines(pairs, figure_rules, a, b, sys.stdout)
    else:
        table(pairs, figure_rules, a, b, sys.stdout)
    if args.html is not None:
        from typing import IO, cast

        from analyzer.compare.page import render
        from analyzer.output_file import OutputFile

        page = render(a, b, pairs, figure_rules, args.time_zone).encode("utf-8")
        with OutputFile(args.html, force=args.force, inputs=[args.a, args.b]) as out:
            cast("IO[bytes]", out.file).write(page)
        print(f"comparison written to {args.html}", file=sys.stderr if args.json else sys.stdout)
    return 1 if any(p.differs for p in pairs) else 0


def judge(path: str, settings: Settings, port: int, *, quiet: bool) -> Judged:
    """``path`` judged by the response analysis (and its video, if it has one), with a
    check recording's steps and a replay's span."""
    from analyzer.analysis.stage import Analysis
    from analyzer.check.output import recorded_steps
    from analyzer.commands.input_pass import read_through
    from analyzer.compare.judged import Judged, Judgements

    judgements = Judgements()
    stages = Analysis.of_file(path, settings).stages()
    reader = read_through(path, [judgements], stages=stages, port=port, quiet=quiet)
    if judgements.first is not None and judgements.first == judgements.last:
        raise UsageError(f"{path} carries no timestamps: its responses cannot be timed")
    described = reader.format_name
    steps = []
    if reader.format_name == "mcap":
        from analyzer.mcapio.channels import METADATA_NAME
        from analyzer.mcapio.read.reader import McapRecording

        command = McapRecording(path).metadata().get(METADATA_NAME, {}).get("command")
        described = f"mcap of {command}" if command else described
        steps = recorded_steps(path)
    return Judged.of(path, described, judgements, steps, settings.tolerance_deg)
