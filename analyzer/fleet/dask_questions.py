"""``fleet --dask``: the standard questions rendered to dask.dataframe and run on a cluster.

Each description (analyzer.fleet.questions) becomes a groupby-aggregation (or a top-N
reduction) over frames the workers read from the Parquet files: the filtering, joining,
grouping and aggregating (medians by a shuffle) run on the workers, and only the
aggregated rows come back. DuckDB then finishes them here with the same SQL as the laptop
path (rates, rounding, order, limit), so both give the same answers.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import pyarrow as pa

from analyzer.errors import UsageError
from analyzer.fleet.columns import RECORDINGS, recordings_schema
from analyzer.fleet.dask_tables import table_frame, table_schema
from analyzer.fleet.dataset import Dataset
from analyzer.fleet.queries import (
    Answer,
    connect,
    finish_sql,
    finish_top_sql,
    group_sql,
    in_memory,
    run_sql,
)
from analyzer.fleet.questions import (
    JOINED,
    Column,
    Constant,
    GroupQuestion,
    Question,
    TopQuestion,
    Where,
)
from analyzer.fleet.runner import cluster_error

if TYPE_CHECKING:
    import dask.dataframe as dd
    import pandas as pd
    from distributed import Client

ONE = "_one"  # a column of 1s: count(*) is its sum
NEAR = 1e-9  # scores this close (relatively) to the last one kept are kept too
Compute = Callable[["dd.DataFrame"], "pd.DataFrame"]


@dataclass
class ClusterRun:
    """What came back from the cluster: the answers and how many aggregated rows."""

    answers: list[Answer]
    rows_back: int = 0


def cluster_tags(dataset: Dataset) -> list[str]:
    """The --tag columns of the recordings table (from the files' schemas)."""
    schema = table_schema(dataset, RECORDINGS)
    standard = set(recordings_schema([]).names)
    return [] if schema is None else [n for n in schema.names if n not in standard]


def on_client(client: Client) -> Compute:
    """Computing on the cluster of ``client``: only the result comes here."""

    def compute(lazy: dd.DataFrame) -> pd.DataFrame:
        try:
            result: pd.DataFrame = client.compute(lazy).result()
        except Exception as exc:  # a task's failure, or a cluster without the package
            raise cluster_error(client, exc) from None
        return result

    return compute


def ask_on_cluster(
    root: str,
    compute: Compute,
    questions: list[Question],
    run: ClusterRun | None = None,
    spread: int = 1,
) -> ClusterRun:
    """Answer ``questions`` with their heavy part done by ``compute`` (on_client: the
    cluster's workers), each table read in at least ``spread`` partitions."""
    dataset = Dataset(root)
    if not dataset.hashes():
        raise UsageError(f"{root} holds no fleet dataset (make one with `gimbal-analyzer table`)")
    run = run or ClusterRun([])
    finisher = in_memory()
    schemas: dict[str, pa.Schema | None] = {}  # each table's footers read once
    for question in questions:
        tables = [question.table]
        if isinstance(question, GroupQuestion) and question.join is not None:
            tables.append(question.join.table)
        for table in tables:
            if table not in schemas:
                schemas[table] = table_schema(dataset, table)
        if any(schemas[t] is None for t in tables):
            # A table with no rows at all: nothing to send out, the empty answer is asked here.
            answer = run_sql(connect(root), _laptop_sql(question), question.title)
        else:
            if isinstance(question, TopQuestion):
                lazy = top_frame(dataset, question, schemas, spread)
            else:
                lazy = group_frame(dataset, question, schemas, spread)
            back = compute(lazy)
            run.rows_back += len(back)
            finisher.register("agg_rows", pa.Table.from_pandas(back, preserve_index=False))
            sql = (
                finish_top_sql(question, "agg_rows")
                if isinstance(question, TopQuestion)
                else finish_sql(question, "agg_rows")
            )
            answer = run_sql(finisher, sql, question.title)
            finisher.unregister("agg_rows")
        answer.name = question.name
        run.answers.append(answer)
    return run


def _laptop_sql(question: Question) -> str:
    if isinstance(question, TopQuestion):
        return finish_top_sql(question, f'"{question.table}"')
    return finish_sql(question, f"({group_sql(question)})")


# -- a description rendered to dask.dataframe ------------------------------------------------


def _mask(frame: pd.DataFrame, where: Where) -> pd.Series:
    column = frame[where.column.source]
    if where.test == "null":
        return column.isna()
    if where.test == "not_null":
        return column.notna()
    same = (column == where.value).fillna(False).astype(bool)
    return same if where.test == "equal" else ~same & column.notna()


def _prepare(frame: pd.DataFrame, question: GroupQuestion) -> pd.DataFrame:
    """One partition: filtered, with the key columns and the columns the aggregates sum."""
    import pandas as pd

    for where in question.where:
        frame = frame[_mask(frame, where)]
    out = pd.DataFrame(index=frame.index)
    for n, key in enumerate(question.keys):
        expr = key.expr
        if isinstance(expr, Column):
            out[f"_k{n}"] = frame[expr.source]
        elif isinstance(expr, Constant):
            text = pd.ArrowDtype(pa.string())
            out[f"_k{n}"] = pd.Series(expr.value, index=frame.index, dtype=text)
        else:
            week = frame[expr.column.source].dt.strftime("%G-W%V")
            out[f"_k{n}"] = week.astype(pd.ArrowDtype(pa.string()))
    out[ONE] = pd.Series(1, index=frame.index, dtype="int64")
    for n, agg in enumerate(question.aggregates):
        if agg.column is None:
            continue
        values = frame[agg.column.source]
        if agg.func == "count_equal":
            values = (values == agg.value).fillna(False).astype("int64")
        elif agg.plus is not None:
            values = values + frame[agg.plus.source]
        out[f"_a{n}"] = values
    return out


def _spec(question: GroupQuestion) -> dict[str, list[str]]:
    spec: dict[str, list[str]] = {ONE: ["sum"]}
    for n, agg in enumerate(question.aggregates):
        if agg.column is None:
            continue
        func = {"count_equal": "sum"}.get(agg.func, agg.func)
        # Sums also count their values: a sum of no values is null, as in SQL.
        spec[f"_a{n}"] = [func, "count"] if func == "sum" else [func]
    return spec


Schemas = dict[str, "pa.Schema | None"]


def group_frame(
    dataset: Dataset, question: GroupQuestion, schemas: Schemas, spread: int = 1
) -> dd.DataFrame:
    """The question's aggregated rows as a lazy frame (small once computed)."""
    main, joined = question.columns()
    schema = schemas[question.table]
    assert schema is not None
    frame = table_frame(dataset, question.table, main, schema, spread)
    if question.join is not None:
        join = question.join
        other_schema = schemas[join.table]
        assert other_schema is not None
        other = table_frame(dataset, join.table, [join.on, *joined], other_schema)
        # One partition (a file per recording would make a merge per pair of partitions).
        other = other.rename(columns={n: JOINED + n for n in joined}).repartition(npartitions=1)
        # The joined table is the small one (one row per recording): sent to every partition.
        frame = frame.merge(other, on=join.on, how="inner", broadcast=True)
    meta = _prepare(frame._meta, question)
    prepared = frame.map_partitions(_prepare, question, meta=meta)
    keys = [f"_k{n}" for n in range(len(question.keys))]
    grouped = prepared.groupby(keys, dropna=False, sort=False).agg(_spec(question))
    return grouped.map_partitions(_named, question)


def _named(grouped: pd.DataFrame, question: GroupQuestion) -> pd.DataFrame:
    """The aggregated columns under the names the finishing SQL reads."""
    import pandas as pd

    flat = grouped.reset_index()
    out = pd.DataFrame(index=flat.index)
    for n, key in enumerate(question.keys):
        out[key.name] = flat[(f"_k{n}", "")]
    for n, agg in enumerate(question.aggregates):
        if agg.column is None:
            out[agg.name] = flat[(ONE, "sum")]
            continue
        func = {"count_equal": "sum"}.get(agg.func, agg.func)
        values = flat[(f"_a{n}", func)]
        if func == "sum" and agg.func == "sum":
            values = values.where(flat[(f"_a{n}", "count")] > 0)
        out[agg.name] = values
    return out


def _best(frame: pd.DataFrame, question: TopQuestion) -> pd.DataFrame:
    """The best rows (score above 0, at most ``limit``) of a partition, or of the best of
    several partitions: the score as the finishing SQL computes it, term by term."""
    total: pd.Series | None = None
    for term in question.score:
        column = frame[term.column]
        if term.present:
            part = column.notna().astype("int64") * term.weight
        elif term.minus is not None:
            part = (column - frame[term.minus]).fillna(0) * term.weight
        else:
            part = column.fillna(0) * term.weight
        total = part if total is None else total + part
    assert total is not None
    score = total.astype("float64")
    kept = frame.assign(_score=score)[score > 0]
    kept = kept.sort_values(["_score", question.tie], ascending=[False, True], kind="stable")
    if len(kept) > question.limit:
        # The best ``limit``, and any row that scores the same give or take the last bit.
        last = float(kept["_score"].iloc[question.limit - 1])
        kept = kept[kept["_score"] >= last - NEAR * max(1.0, abs(last))]
    best: pd.DataFrame = kept.drop(columns="_score")
    return best


def top_frame(
    dataset: Dataset, question: TopQuestion, schemas: Schemas, spread: int = 1
) -> dd.DataFrame:
    """The rows the top question can show (at most its limit), as a tree reduction."""
    schema = schemas[question.table]
    assert schema is not None
    frame = table_frame(dataset, question.table, question.columns(), schema, spread)
    kwargs = {"question": question}
    return frame.reduction(
        _best,
        aggregate=_best,
        combine=_best,
        meta=frame._meta,
        chunk_kwargs=kwargs,
        aggregate_kwargs=kwargs,
        combine_kwargs=kwargs,
    )
