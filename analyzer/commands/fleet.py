"""``gimbal-analyzer fleet``: the fleet's standard questions, or any SQL, over a dataset."""

from __future__ import annotations

import argparse
import sys
from typing import IO, TYPE_CHECKING, cast

from analyzer.errors import UsageError

if TYPE_CHECKING:
    from analyzer.fleet.queries import Answer

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
  gimbal-analyzer fleet fleet/ --question worst_flights --csv
  gimbal-analyzer fleet fleet/ --sql "SELECT gimbal, avg(crc_error_rate) FROM recordings GROUP BY 1"
  gimbal-analyzer fleet fleet/ --sql "SELECT * FROM findings WHERE verdict = 'not_obeyed'" --csv
  gimbal-analyzer fleet fleet/ --html fleet.html
  gimbal-analyzer fleet fleet/ --dask tcp://scheduler:8786

--dask runs the same questions on a Dask cluster (pip install
'gimbal-analyzer[cluster]'): its workers read the Parquet files (they must reach
DIR by the same path), filter, join, group and aggregate there with
dask.dataframe (medians by a shuffle), and only the aggregated rows come back;
DuckDB finishes them here (rates, rounding, order) with the same SQL as without
--dask, so the answers are the same. --sql with --dask is not spread over the
cluster (arbitrary SQL cannot in general be cut into worker tasks): the workers
read the tables the query names, only the columns it names (every column when it
has a * or NATURAL JOIN), and the query runs here over those rows.

  gimbal-analyzer fleet fleet/ --dask tcp://scheduler:8786 --sql "SELECT ..."

Times are UTC (--local-time: local time with its offset in the text and the
report; JSON and CSV keep UTC). Weeks are ISO weeks in UTC.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("dataset", metavar="DIR", help="a dataset folder made by `table`")
    parser.add_argument("--sql", metavar="QUERY", help="run this query instead")
    shape = parser.add_mutually_exclusive_group()
    shape.add_argument("--json", action="store_true", help="rows as JSON lines")
    shape.add_argument("--csv", action="store_true", help="rows as CSV")
    parser.add_argument(
        "--question",
        metavar="NAME",
        help="only this standard question (its name as --json gives it, e.g. worst_flights); "
        "--csv needs it: one table per CSV",
    )
    parser.add_argument("--html", metavar="FILE", help="write the fleet report to FILE")
    parser.add_argument(
        "-f", "--force", action="store_true", help="replace the --html file if it exists"
    )
    parser.add_argument(
        "--dask",
        metavar="ADDRESS",
        help="run the questions on this Dask scheduler's workers (tcp://HOST:8786)",
    )


def run(args: argparse.Namespace) -> int:
    from analyzer.extras import FLEET, require

    require(FLEET, "`fleet`")
    from analyzer.fleet.output import write_csv, write_json, write_text
    from analyzer.output_file import OutputFile, check_output

    if args.html:
        check_output(args.html, force=args.force)
    if args.question and args.sql:
        raise UsageError("--question picks a standard question; --sql asks its own")
    standard: list[Answer] = []
    overview: Answer | None = None
    query: list[Answer] = []
    if args.dask:
        standard, overview, query = _on_cluster(args)
    else:
        from analyzer.fleet.queries import ask, connect, run_sql, standard_answers
        from analyzer.fleet.questions import overview as overview_question

        con = connect(args.dataset)
        if args.sql:
            query = [run_sql(con, args.sql, f"Query: {args.sql}")]
        if not args.sql or args.html:
            standard = standard_answers(con)
        if args.html:
            overview = ask(con, overview_question())
    answers = query or _chosen(standard, args)
    out = sys.stdout
    if args.json:
        write_json(out, answers, named=not args.sql)
    elif args.csv:
        write_csv(out, answers[0])
    elif not args.html or args.sql:
        write_text(out, answers, args.time_zone)
    if args.html:
        from analyzer.fleet.page import render_fleet

        assert overview is not None
        # With --sql, the standard page with the query's answer at the end.
        page = render_fleet(
            args.dataset, standard, overview, extra=query, zone=args.time_zone
        ).encode()
        with OutputFile(args.html, force=args.force) as handle:
            cast("IO[bytes]", handle.file).write(page)
        sys.stderr.write(f"wrote {args.html} ({len(page) / 1024:,.0f} KiB)\n")
    return 0


def _chosen(answers: list[Answer], args: argparse.Namespace) -> list[Answer]:
    """The answer --question names (every answer without it); --csv takes one table."""
    names = ", ".join(a.name for a in answers)
    if args.question:
        picked = [a for a in answers if a.name == args.question]
        if not picked:
            raise UsageError(f"--question {args.question}: no such question here; one of: {names}")
        return picked
    if args.csv and len(answers) > 1:
        raise UsageError(f"--csv writes one table: choose it with --question NAME, one of: {names}")
    return answers


def _on_cluster(args: argparse.Namespace) -> tuple[list[Answer], Answer | None, list[Answer]]:
    """The standard answers, the report's overview (with --html) and the --sql answer,
    with the work on the cluster at ``args.dask``."""
    from analyzer.fleet.dask_questions import (
        ClusterRun,
        ask_on_cluster,
        cluster_tags,
        on_client,
    )
    from analyzer.fleet.dask_tables import dask_tables, tables_named, workers
    from analyzer.fleet.dataset import Dataset
    from analyzer.fleet.queries import connect, run_sql
    from analyzer.fleet.questions import Question, overview, standard_questions
    from analyzer.fleet.runner import connect as connect_cluster

    client = connect_cluster(args.dask)
    try:
        query: list[Answer] = []
        if args.sql:
            tables = dask_tables(args.dataset, client, tables_named(args.sql))
            con = connect(args.dataset, tables)
            query = [run_sql(con, args.sql, f"Query: {args.sql}")]
            rows = sum(t.num_rows for t in tables.values())
            read = "; ".join(f"{n} ({', '.join(t.column_names)})" for n, t in tables.items())
            sys.stderr.write(
                f"fleet: the workers of {args.dask} read {read or 'no table'}; "
                f"{rows:,} rows came back and the query ran here\n"
            )
        questions: list[Question] = []
        if not args.sql or args.html:
            questions = list(standard_questions(cluster_tags(Dataset(args.dataset))))
        if args.html:
            questions.append(overview())
        if not questions:
            return [], None, query
        spread = workers(client)
        run = ask_on_cluster(args.dataset, on_client(client), questions, ClusterRun([]), spread)
        sys.stderr.write(
            f"fleet: {len(questions)} question(s) aggregated on the workers of {args.dask}; "
            f"{run.rows_back:,} aggregated rows came back\n"
        )
    finally:
        client.close()
    answers = run.answers
    if args.html:
        return answers[:-1], answers[-1], query
    return answers, None, query
