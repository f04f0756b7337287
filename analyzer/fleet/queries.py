"""The fleet's questions rendered to SQL and answered by embedded DuckDB over the dataset."""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime
from typing import TYPE_CHECKING

from analyzer.errors import UsageError
from analyzer.fleet.columns import RECORDINGS, TABLES, empty_table, recordings_schema
from analyzer.fleet.dataset import Dataset
from analyzer.fleet.questions import (
    JOINED,
    Aggregate,
    Column,
    Constant,
    GroupQuestion,
    IsoWeek,
    Question,
    TopQuestion,
    Where,
    standard_questions,
)

if TYPE_CHECKING:
    import duckdb
    import pyarrow as pa

Value = str | int | float | bool | datetime | None


@dataclass
class Answer:
    """One question's result: a title, its column names and rows."""

    name: str
    title: str
    columns: list[str]
    rows: list[tuple[Value, ...]]


def connect(root: str, tables: dict[str, pa.Table] | None = None) -> duckdb.DuckDBPyConnection:
    """An in-memory DuckDB with one view per table of the dataset at ``root``.

    ``tables`` replaces files by tables already in memory (what ``fleet --dask --sql``
    brought from the workers).
    """
    dataset = Dataset(root)
    if tables is None and not dataset.hashes():
        raise UsageError(f"{root} holds no fleet dataset (make one with `gimbal-analyzer table`)")
    con = in_memory()
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


def in_memory() -> duckdb.DuckDBPyConnection:
    """An empty in-memory DuckDB that works in UTC (weeks and dates, as every time shown)."""
    import duckdb

    con = duckdb.connect(":memory:")
    con.execute("SET TimeZone = 'UTC'")
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


def q(name: str) -> str:
    """A quoted SQL identifier."""
    return '"' + name.replace('"', '""') + '"'


def literal(text: str) -> str:
    return "'" + text.replace("'", "''") + "'"


def standard_answers(con: duckdb.DuckDBPyConnection) -> list[Answer]:
    """The standard questions (analyzer.fleet.questions) asked of the dataset here."""
    return [ask(con, question) for question in standard_questions(tag_columns(con))]


def ask(con: duckdb.DuckDBPyConnection, question: Question) -> Answer:
    """One described question, rendered to SQL and answered by DuckDB."""
    if isinstance(question, TopQuestion):
        sql = finish_top_sql(question, q(question.table))
    else:
        sql = finish_sql(question, f"({group_sql(question)})")
    answer = run_sql(con, sql, question.title)
    answer.name = question.name
    return answer


# -- a description rendered to SQL ---------------------------------------------------------


def _column(column: Column) -> str:
    return q(column.source)


def _key(expr: Column | Constant | IsoWeek) -> str:
    if isinstance(expr, Column):
        return _column(expr)
    if isinstance(expr, Constant):
        return literal(expr.value)
    return f"strftime(date_trunc('week', {_column(expr.column)}), '%G-W%V')"


def _where(where: Where) -> str:
    column = _column(where.column)
    if where.test == "null":
        return f"{column} IS NULL"
    if where.test == "not_null":
        return f"{column} IS NOT NULL"
    operator = "=" if where.test == "equal" else "<>"
    return f"{column} {operator} {literal(str(where.value))}"


def _aggregate(agg: Aggregate) -> str:
    column = _column(agg.column) if agg.column is not None else "*"
    if agg.func == "count":
        return f"count({column})"
    if agg.func == "count_equal":
        return f"count(*) FILTER (WHERE {column} = {literal(str(agg.value))})"
    if agg.plus is not None:
        column = f"{column} + {_column(agg.plus)}"
    return f"{agg.func}({column})"


def source_sql(question: GroupQuestion) -> str:
    """The question's rows: its table's columns it reads, joined, filtered."""
    main, joined = question.columns()
    names = [f"t.{q(n)}" for n in main]
    origin = f"{q(question.table)} t"
    if question.join is not None:
        join = question.join
        names += [f"j.{q(n)} AS {q(JOINED + n)}" for n in joined]
        inner = ", ".join(q(n) for n in [join.on, *joined])
        on = q(join.on)
        origin += f" JOIN (SELECT {inner} FROM {q(join.table)}) j ON t.{on} = j.{on}"
    sql = f"SELECT {', '.join(names) or '1'} FROM {origin}"
    if question.where:
        sql = f"SELECT * FROM ({sql}) WHERE " + " AND ".join(_where(w) for w in question.where)
    return sql


def group_sql(question: GroupQuestion) -> str:
    """The aggregation (what ``fleet --dask`` computes on the workers instead)."""
    keys = [f"{_key(k.expr)} AS {q(k.name)}" for k in question.keys]
    aggs = [f"{_aggregate(a)} AS {q(a.name)}" for a in question.aggregates]
    positions = ", ".join(str(n + 1) for n in range(len(keys)))
    return f"SELECT {', '.join(keys + aggs)} FROM ({source_sql(question)}) GROUP BY {positions}"


def finish_sql(question: GroupQuestion, source: str) -> str:
    """The answer from the aggregated rows in ``source``: rates, rounding, order, limit.
    The same on both paths, over few rows."""
    shown = []
    for out in question.outputs:
        value = q(out.of)
        if out.over is not None:
            value = f"CAST({value} AS DOUBLE) / nullif(CAST({q(out.over)} AS DOUBLE), 0)"
        if out.digits is not None:
            value = f"round({value}, {out.digits})"
        shown.append(f"{value} AS {q(out.name)}")
    sql = f"SELECT {', '.join(shown)} FROM {source} agg"
    if question.order:
        order = [
            f"{q(o.name)} {'DESC' if o.descending else 'ASC'} NULLS LAST" for o in question.order
        ]
        sql += " ORDER BY " + ", ".join(order)
    if question.limit is not None:
        sql += f" LIMIT {question.limit}"
    return sql


def score_sql(question: TopQuestion) -> str:
    terms = []
    for term in question.score:
        column = f"r.{q(term.column)}"
        if term.present:
            terms.append(f"(CASE WHEN {column} IS NOT NULL THEN {term.weight} ELSE 0 END)")
        elif term.minus is not None:
            terms.append(f"coalesce({column} - r.{q(term.minus)}, 0) * {term.weight}")
        else:
            terms.append(f"coalesce({column}, 0) * {term.weight}")
    return "(" + " + ".join(terms) + ")"


def finish_top_sql(question: TopQuestion, source: str) -> str:
    """The top rows of ``source`` by score (unrounded: the rounded one is for people) with
    the reasons (the same on both paths)."""
    score = score_sql(question)
    shown = "".join(f"r.{q(c)}, " for c in question.shown)
    reason = ", ".join(f"CASE WHEN {r.when} THEN {r.text} END" for r in question.reasons)
    return (
        f"SELECT {shown}round({score}, 1) AS score, concat_ws('; ', {reason}) AS reason "
        f"FROM {source} r WHERE {score} > 0 "
        f"ORDER BY {score} DESC, r.{q(question.tie)} LIMIT {question.limit}"
    )
