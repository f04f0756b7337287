"""``gimbal-analyzer fleet``: the fleet's standard questions, or any SQL, over a dataset."""

from __future__ import annotations

import argparse
import sys
from typing import IO, cast

HELP = "ask a fleet dataset (from `table`): CRC errors, gaps, obedience, worst flights, any SQL"

DESCRIPTION = """\
Answers the standard questions over a dataset `gimbal-analyzer table` made,
with DuckDB inside this process (no server):

  CRC error rate and feedback gaps per tag value (gimbal, aircraft, firmware,
  whatever --tag gave) and per week, obedience (verdict counts and median
  response time) per command and tag, and the worst flights with the reason.

--sql runs any query over views named after the tables (recordings, commands,
attitude, ranging, uav_gps, uav_altitude, uav_attitude, uav_text, diagnostics,
findings); join them on content_hash. --html writes the answers as a report
with plots, in the style of `report` (with --sql, the query's answer at its end).

  gimbal-analyzer fleet fleet/
  gimbal-analyzer fleet fleet/ --json
  gimbal-analyzer fleet fleet/ --sql "SELECT gimbal, avg(crc_error_rate) FROM recordings GROUP BY 1"
  gimbal-analyzer fleet fleet/ --sql "SELECT * FROM findings WHERE verdict = 'not_obeyed'" --csv
  gimbal-analyzer fleet fleet/ --html fleet.html
  gimbal-analyzer fleet fleet/ --dask tcp://scheduler:8786

--dask reads the tables with dask.dataframe on the cluster's workers (they must
reach DIR by the same path), cuts them there to the columns the questions need,
and answers from that here; with --sql it brings the tables the query names.
Times are UTC.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("dataset", metavar="DIR", help="a dataset folder made by `table`")
    parser.add_argument("--sql", metavar="QUERY", help="run this query instead")
    shape = parser.add_mutually_exclusive_group()
    shape.add_argument("--json", action="store_true", help="rows as JSON lines")
    shape.add_argument("--csv", action="store_true", help="rows as CSV")
    parser.add_argument("--html", metavar="FILE", help="write the fleet report to FILE")
    parser.add_argument("--force", action="store_true", help="replace the --html file if it exists")
    parser.add_argument(
        "--dask", metavar="ADDRESS", help="read the tables on this Dask scheduler (tcp://HOST:8786)"
    )


def run(args: argparse.Namespace) -> int:
    from analyzer.fleet.output import write_csv, write_json, write_text
    from analyzer.fleet.queries import connect, run_sql, standard_questions
    from analyzer.output_file import OutputFile, check_output

    if args.html:
        check_output(args.html, force=args.force)
    tables = None
    if args.dask:
        from analyzer.fleet.dask_tables import dask_tables, tables_named

        wanted = tables_named(args.sql) if args.sql else None
        tables = dask_tables(args.dataset, args.dask, wanted)
    con = connect(args.dataset, tables)
    answers = (
        [run_sql(con, args.sql, f"Query: {args.sql}")] if args.sql else standard_questions(con)
    )
    out = sys.stdout
    if args.json:
        write_json(out, answers, named=not args.sql)
    elif args.csv:
        write_csv(out, answers, named=not args.sql)
    elif not args.html or args.sql:
        write_text(out, answers)
    if args.html:
        from analyzer.fleet.page import render_fleet

        if args.sql:  # the standard page, with the query's answer at the end
            page = render_fleet(con, args.dataset, extra=answers).encode()
        else:
            page = render_fleet(con, args.dataset, answers).encode()
        with OutputFile(args.html, force=args.force) as handle:
            cast("IO[bytes]", handle.file).write(page)
        sys.stderr.write(f"wrote {args.html} ({len(page) / 1024:,.0f} KiB)\n")
    return 0
