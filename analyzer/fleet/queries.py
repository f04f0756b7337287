"""The fleet's questions in SQL, answered by embedded DuckDB over the Parquet dataset."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime
from typing import TYPE_CHECKING

from analyzer.errors import UsageError
from analyzer.fleet.columns import RECORDINGS, TABLES, empty_table, recordings_schema
from analyzer.fleet.dataset import Dataset

if TYPE_CHECKING:
    import duckdb
    import pyarrow as pa

Value = str | int | float | bool | datetime | None
WORST = 10  # flights in the worst-flights list
CRC_ALARM = 0.01  # a CRC error rate above this is a reason to look at a flight


@dataclass
class Answer:
    """One question's result: a title, its column names and rows."""

    name: str
    title: str
    columns: list[str]
    rows: list[tuple[Value, ...]]


def connect(root: str, tables: dict[str, pa.Table] | None = None) -> duckdb.DuckDBPyConnection:
    """An in-memory DuckDB with one view per table of the dataset at ``root``.

    ``tables`` replaces files by tables already in memory (what ``fleet --dask`` computed).
    """
    import duckdb

    dataset = Dataset(root)
    if tables is None and not dataset.hashes():
        raise UsageError(f"{root} holds no fleet dataset (make one with `gimbal-analyzer table`)")
    con = duckdb.connect(":memory:")
    con.execute("SET TimeZone = 'UTC'")  # weeks and dates are UTC, as every time shown
    for name in TABLES:
        given = (tables or {}).get(name)
        files = [str(p) for p in dataset.files(name)] if tables is None else []
        if given is not None:
            con.register(f"_{name}", given)
            con.execute(f'CREATE VIEW "{name}" AS SELECT * FROM "_{name}"')
        elif files:
            listed = ", ".join("'" + f.replace("'", "''") + "'" for f in files)
            con.execute(
                f'CREATE VIEW "{name}" AS SELECT * FROM read_parquet([{listed}], '
                "union_by_name = true)"
            )
        else:
            con.register(f"_{name}", empty_table(name))
            con.execute(f'CREATE VIEW "{name}" AS SELECT * FROM "_{name}"')
    return con


def tag_columns(con: duckdb.DuckDBPyConnection) -> list[str]:
    """The --tag columns of the recordings table (those that are not standard columns)."""
    standard = set(recordings_schema([]).names)
    names = [row[0] for row in con.execute(f'DESCRIBE "{RECORDINGS}"').fetchall()]
    return [n for n in names if n not in standard]


def run_sql(con: duckdb.DuckDBPyConnection, sql: str, title: str = "query") -> Answer:
    """Any query; a DuckDB error becomes a UsageError with its first line."""
    import duckdb

    try:
        cursor = con.execute(sql)
        rows = cursor.fetchall()
    except duckdb.Error as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise UsageError(f"SQL: {first}") from None
    columns = [d[0] for d in cursor.description or []]
    return Answer("sql", title, columns, [tuple(r) for r in rows])


def _q(name: str) -> str:
    return '"' + name.replace('"', '""') + '"'


def standard_questions(con: duckdb.DuckDBPyConnection) -> list[Answer]:
    """CRC and gaps per tag and per week, obedience per command and tag, the worst flights."""
    tags = tag_columns(con)
    groups: list[tuple[str, str]] = [(t, f"r.{_q(t)}") for t in tags] or [("fleet", "'all'")]
    answers: list[Answer] = []
    link = (
        "count(*) AS flights, sum(r.crc_errors) AS crc_errors, "
        "sum(r.crc_checked + r.crc_errors) AS crc_protected, "
        "round(sum(r.crc_errors) / nullif(sum(r.crc_checked + r.crc_errors), 0), 6) "
        "AS crc_error_rate, sum(r.gaps) AS gaps, round(max(r.longest_gap_s), 3) AS longest_gap_s"
    )
    for tag, expr in groups:
        answers.append(
            _ask(
                con,
                f"link_by_{tag}",
                f"CRC error rate and feedback gaps per {tag}",
                f"SELECT {expr} AS {_q(tag)}, {link} FROM recordings r WHERE r.error IS NULL "
                "GROUP BY 1 ORDER BY crc_error_rate DESC NULLS LAST, 1",
            )
        )
    for tag, expr in groups:
        answers.append(
            _ask(
                con,
                f"link_by_week_{tag}",
                f"CRC error rate and feedback gaps per week and {tag}",
                f"SELECT strftime(date_trunc('week', r.start), '%G-W%V') AS week, "
                f"{expr} AS {_q(tag)}, {link} FROM recordings r "
                "WHERE r.error IS NULL GROUP BY 1, 2 ORDER BY 1, 2",
            )
        )
    for tag, expr in groups:
        answers.append(
            _ask(
                con,
                f"obedience_by_{tag}",
                f"Obedience per command and {tag}",
                f"SELECT f.command, {expr} AS {_q(tag)}, count(*) AS findings, "
                "count(*) FILTER (f.verdict = 'obeyed') AS obeyed, "
                "count(*) FILTER (f.verdict = 'partial') AS partial, "
                "count(*) FILTER (f.verdict = 'not_obeyed') AS not_obeyed, "
                "count(*) FILTER (f.verdict = 'unknown') AS unknown, "
                "round(median(f.response_s), 3) AS median_response_s "
                "FROM findings f JOIN recordings r USING (content_hash) "
                "WHERE f.command <> 'feedback' GROUP BY 1, 2 ORDER BY 1, 2",
            )
        )
    answers.append(_worst(con, tags))
    return answers


def _worst(con: duckdb.DuckDBPyConnection, tags: Sequence[str]) -> Answer:
    shown = "".join(f"r.{_q(t)}, " for t in tags)
    reason = (
        "concat_ws('; ', "
        "CASE WHEN r.error IS NOT NULL THEN 'unreadable: ' || r.error END, "
        f"CASE WHEN r.crc_error_rate > {CRC_ALARM} THEN 'CRC errors ' || "
        "round(r.crc_error_rate * 100, 2) || ' %' END, "
        "CASE WHEN r.findings_not_obeyed > 0 THEN "
        "r.findings_not_obeyed || ' finding(s) not obeyed' END, "
        "CASE WHEN r.findings_partial > 0 THEN r.findings_partial || ' partial' END, "
        "CASE WHEN r.gaps > 0 THEN r.gaps || ' feedback gap(s), longest ' || "
        "round(r.longest_gap_s, 1) || ' s' END, "
        "CASE WHEN r.diagnostics > r.crc_errors THEN (r.diagnostics - r.crc_errors) || "
        "' other diagnostic(s)' END)"
    )
    score = (
        "(CASE WHEN r.error IS NOT NULL THEN 1000 ELSE 0 END"
        " + coalesce(r.crc_error_rate, 0) * 1000 + coalesce(r.findings_not_obeyed, 0) * 10"
        " + coalesce(r.findings_partial, 0) * 3 + coalesce(r.gaps, 0) * 5"
        " + coalesce(r.diagnostics - r.crc_errors, 0))"
    )
    return _ask(
        con,
        "worst_flights",
        f"The worst flights (at most {WORST})",
        f"SELECT r.recording, {shown}strftime(r.start, '%Y-%m-%dT%H:%M:%SZ') AS start, "
        f"round({score}, 1) AS score, {reason} AS reason FROM recordings r "
        f"WHERE {score} > 0 ORDER BY score DESC, r.recording LIMIT {WORST}",
    )


def _ask(con: duckdb.DuckDBPyConnection, name: str, title: str, sql: str) -> Answer:
    answer = run_sql(con, sql, title)
    answer.name = name
    return answer
