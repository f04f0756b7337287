"""The standard questions, described once, give the same answers rendered to DuckDB SQL and
to dask.dataframe, on any dataset: nulls, untagged runs, medians of even counts, ties."""

from __future__ import annotations

import tempfile
from dataclasses import replace
from datetime import datetime, timedelta, timezone
from typing import Any

import pyarrow as pa
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from analyzer.fleet.columns import RECORDINGS, event_schema, recordings_schema
from analyzer.fleet.dataset import Dataset
from analyzer.fleet.queries import Answer, ask, connect, finish_sql, group_sql, standard_answers
from analyzer.fleet.questions import overview, standard_questions, worst_flights
from analyzer.protocol.types import TOPIC_ANALYSIS_RESPONSE

dd = pytest.importorskip("dask.dataframe")  # the cluster extra

from analyzer.fleet.dask_questions import ask_on_cluster, cluster_tags  # noqa: E402

START = datetime(2023, 11, 13, tzinfo=timezone.utc)  # a Monday
COMMANDS = ("tracking", "look_down", "specified_angle", "feedback")
VERDICTS = ("obeyed", "partial", "not_obeyed", "unknown")
# Response times with ties and many digits, as measured ones have.
RESPONSES = st.none() | st.sampled_from([0.5, 1.0, 1.25, 0.333333, 2.0000005, 0.1 + 0.2])

finding = st.fixed_dictionaries(
    {"command": st.sampled_from(COMMANDS), "verdict": st.sampled_from(VERDICTS)}
).flatmap(lambda f: st.builds(lambda r: {**f, "response_s": r}, RESPONSES))

flight = st.fixed_dictionaries(
    {
        "gimbal": st.sampled_from(["A", "B", None]),
        "tagged": st.booleans(),  # a run with --tag gimbal=..., or one without tags
        "hours": st.none() | st.integers(0, 24 * 20),
        "error": st.sampled_from([None, None, None, "cannot read x: gone"]),
        "crc_checked": st.integers(0, 500),
        "crc_errors": st.integers(0, 40),
        "gaps": st.integers(0, 3),
        "longest_gap_s": st.none() | st.floats(0.1, 9.0).map(lambda x: round(x, 4)),
        "not_obeyed": st.integers(0, 2),
        "findings": st.lists(finding, max_size=6),
    }
)


def write_flight(dataset: Dataset, n: int, f: dict[str, Any]) -> None:
    digest = f"{n:064x}"
    start = None if f["hours"] is None else START + timedelta(hours=f["hours"])
    row: dict[str, Any] = {"recording": f"f{n}.log", "content_hash": digest, "error": f["error"]}
    if f["tagged"]:
        row["gimbal"] = f["gimbal"]
    if f["error"] is None:
        protected = f["crc_checked"] + f["crc_errors"]
        row.update(
            start=start,
            end=None if start is None else start + timedelta(seconds=90),
            frames=10 * protected,
            crc_checked=f["crc_checked"],
            crc_errors=f["crc_errors"],
            crc_error_rate=f["crc_errors"] / protected if protected else None,
            gaps=f["gaps"],
            longest_gap_s=f["longest_gap_s"],
            diagnostics=f["crc_errors"] + n % 3,
            findings=len(f["findings"]),
            findings_not_obeyed=f["not_obeyed"],
            findings_partial=n % 2,
        )
    tables = {RECORDINGS: pa.Table.from_pylist([row], recordings_schema(["gimbal"] * f["tagged"]))}
    if f["error"] is None and f["findings"]:
        base = {"recording": row["recording"], "content_hash": digest, "time": start}
        found = [{**base, **x} for x in f["findings"]]
        tables["findings"] = pa.Table.from_pylist(found, event_schema(TOPIC_ANALYSIS_RESPONSE))
    dataset.write(digest, tables)


def strict(answer: Answer) -> list[tuple[tuple[str, object], ...]]:
    """Rows with each value's type: 1 and 1.0 differ here."""
    return [tuple((type(v).__name__, v) for v in row) for row in answer.rows]


def sync(lazy: Any) -> Any:
    return lazy.compute(scheduler="sync")


@pytest.mark.slow
@settings(max_examples=10, deadline=None)
@given(flights=st.lists(flight, min_size=1, max_size=14))
def test_sql_and_dask_renderings_give_the_same_answers(flights: list[dict[str, Any]]) -> None:
    same_answers(flights)


@pytest.mark.slow
def test_worst_flights_close_in_score_are_cut_alike() -> None:
    """Four flights that all show a score of 29.1: the order is the exact score's (the
    shown one is rounded), the same on both paths, whatever the names' order."""
    plain = {
        "gimbal": "A", "tagged": True, "hours": 5, "error": None, "gaps": 0,
        "longest_gap_s": None, "not_obeyed": 0, "findings": [],
    }  # fmt: skip
    flights = [{**plain, "crc_checked": 1000, "crc_errors": 0} for _ in range(19)]
    # Flights 0, 6, 12, 18 score their CRC error rate alone (per mille).
    for n, errors in ((0, 2906), (6, 2914), (12, 2912), (18, 2908)):
        flights[n] = {**plain, "crc_checked": 100_000 - errors, "crc_errors": errors}
    answers = same_answers(flights)
    (worst_3,) = [a for a in answers if a.name == "worst_3"]
    assert [(row[0], row[-2]) for row in worst_3.rows] == [
        ("f6.log", 29.1), ("f12.log", 29.1), ("f18.log", 29.1)
    ]  # fmt: skip


def same_answers(flights: list[dict[str, Any]]) -> list[Answer]:
    """The standard answers (and the worst 3 flights) of a dataset of ``flights``, checked
    to be the same rendered to SQL and to dask.dataframe."""
    with tempfile.TemporaryDirectory() as root:
        dataset = Dataset(root)
        dataset.create()
        for n, f in enumerate(flights):
            write_flight(dataset, n, f)
        con = connect(root)
        tags = cluster_tags(dataset)
        assert tags == (["gimbal"] if any(f["tagged"] for f in flights) else [])
        # The worst flights cut at 3 too: the workers' candidates must hold the answer.
        worst_3 = replace(worst_flights(tags), name="worst_3", limit=3)
        here = [*standard_answers(con), ask(con, overview()), ask(con, worst_3)]
        questions = [*standard_questions(tags), overview(), worst_3]
        there = ask_on_cluster(root, sync, questions, spread=3).answers  # several partitions
        assert [a.name for a in there] == [a.name for a in here]
        for mine, theirs in zip(here, there, strict=True):
            assert theirs.columns == mine.columns, mine.name
            assert strict(theirs) == strict(mine), mine.name
    return here


def test_the_laptop_sql_aggregates_first_then_finishes() -> None:
    """The one description gives the SQL of both steps; the finishing step is what runs
    over the rows the workers send back."""
    link = standard_questions(["gimbal"])[0]
    inner = group_sql(link)
    assert 'sum("crc_checked" + "crc_errors") AS "crc_protected"' in inner
    assert inner.endswith("GROUP BY 1")
    outer = finish_sql(link, "agg_rows")
    assert (
        'round(CAST("crc_errors" AS DOUBLE) / nullif(CAST("crc_protected" AS DOUBLE), 0), 6)'
        ' AS "crc_error_rate"' in outer
    )
    assert outer.endswith('ORDER BY "crc_error_rate" DESC NULLS LAST, "gimbal" ASC NULLS LAST')


def test_sql_on_a_cluster_brings_the_columns_the_query_names() -> None:
    from analyzer.fleet.dask_tables import tables_named

    named = tables_named(
        "SELECT r.gimbal, count(*) FROM findings f JOIN recordings r USING (content_hash)"
    )
    assert set(named) == {"findings", "recordings"}
    assert all(
        words is not None and {"gimbal", "content_hash"} <= words for words in named.values()
    )
    # A query that may take columns it does not name brings them all.
    assert tables_named("SELECT * FROM recordings") == {"recordings": None}
    assert tables_named("SELECT f.* FROM findings f") == {"findings": None}
    assert tables_named("SELECT 1 FROM findings NATURAL JOIN commands") == {
        "commands": None, "findings": None,
    }  # fmt: skip
