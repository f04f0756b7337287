"""The report's bounded summaries: plot series that keep every extreme in bounded memory,
findings counted exactly per command and check with the worst examples kept."""

from __future__ import annotations

import math
import random
from collections import Counter

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from analyzer.report.decimate import Decimator, PerSecond
from analyzer.report.finding_groups import FindingGroups

samples = st.lists(
    st.tuples(
        st.floats(0, 10_000, allow_nan=False),
        st.floats(-1e6, 1e6, allow_nan=False),
        st.floats(-1e6, 1e6, allow_nan=False),
    ),
    min_size=1,
    max_size=400,
)


@settings(max_examples=200, deadline=None)
@given(samples, st.integers(2, 40))
def test_every_bucket_keeps_its_extremes_and_the_buckets_stay_bounded(
    rows: list[tuple[float, float, float]], limit: int
) -> None:
    series = Decimator((1, 2), limit)
    for row in rows:
        series.add(row)
    kept = series.rows()
    assert len(series.buckets) <= limit
    assert len(kept) <= 4 * limit  # the rows with each column's minimum and maximum
    assert all(row in rows for row in kept)  # real samples only
    assert [r[0] for r in kept] == sorted(r[0] for r in kept)
    assert series.count == len(rows)
    assert series.origin is not None
    for column in (1, 2):  # the flight's extremes, and those of every final bucket
        assert min(r[column] for r in kept) == min(r[column] for r in rows)
        assert max(r[column] for r in kept) == max(r[column] for r in rows)
        by_bucket: dict[int, list[float]] = {}
        for row in rows:
            key = math.floor((row[0] - series.origin) / series.width)
            by_bucket.setdefault(key, []).append(row[column])
        for values in by_bucket.values():
            assert min(values) in [r[column] for r in kept]
            assert max(values) in [r[column] for r in kept]


def test_a_short_series_is_kept_whole_and_a_long_one_in_bounded_memory() -> None:
    short = Decimator((1,))
    for i in range(500):
        short.add((i * 0.02, math.sin(i)))
    assert short.whole and len(short.rows()) == 500
    long = Decimator((1,), limit=1000)
    rng = random.Random(3)
    for i in range(200_000):
        long.add((i * 0.01, rng.gauss(0, 1)))
    assert not long.whole and len(long.buckets) <= 1000 and len(long.rows()) <= 2000
    assert long.width == 0.001 * 2**11  # doubled until 2,000 s fit in 1,000 buckets


def test_marks_keep_the_first_of_each_bucket() -> None:
    marks = Decimator((), limit=10)
    for i in range(100):
        marks.add((float(i), f"command {i}"))
    kept = marks.rows()
    assert kept[0][1] == "command 0" and len(kept) == len(marks.buckets) <= 10
    every = Decimator(())
    for i in range(100):
        every.add((i * 0.2, f"command {i}"))
    assert every.whole and len(every.rows()) == 100


def test_events_per_second_count_silent_seconds_as_zero() -> None:
    counts = PerSecond(zeros=True)
    for t in (10.2, 10.7, 11.1, 14.5, 14.6, 14.7):
        counts.add(t)
    rows = counts.rows(until=16.3)
    assert rows == [(10.2, 2), (11.0, 1), (12.0, 0), (13.0, 0), (14.0, 3), (15.0, 0), (16.0, 0)]
    errors = PerSecond(zeros=False)
    for t in (3.5, 9.1, 9.2):
        errors.add(t)
    assert errors.rows() == [(3.5, 1), (9.0, 2)]


def finding(command: str, check: str, verdict: str, t: float, **extra: float) -> dict[str, object]:
    return {"command": command, "check": check, "verdict": verdict, "time": t, **extra}


def test_findings_are_counted_exactly_and_the_worst_are_kept_first() -> None:
    groups = FindingGroups(keep=3)
    rng = random.Random(5)
    made = []
    for i in range(5000):
        verdict = rng.choice(["obeyed", "partial", "not_obeyed", "unknown"])
        made.append(finding("specified_angle", "target", verdict, i, error_deg=rng.uniform(-9, 9)))
    made.append(finding("feedback", "feedback_gap", "not_obeyed", 7.0, gap_s=3.0))
    for f in made:
        groups.add(f)
    assert groups.total == 5001
    assert groups.verdicts == Counter(str(f["verdict"]) for f in made)
    target = groups.groups["specified_angle", "target"]
    assert target.verdicts == Counter(str(f["verdict"]) for f in made[:5000])
    worst = sorted(
        (f for f in made[:5000] if f["verdict"] == "not_obeyed"),
        key=lambda f: abs(float(f["error_deg"])),  # type: ignore[arg-type]
        reverse=True,
    )[:3]
    assert target.examples() == worst
    assert (target.first, target.last) == (0, 4999)
    # groups with the most commands not obeyed first
    assert [g.command for g in groups.ordered()] == ["specified_angle", "feedback"]
    assert groups.worst_first()[0] is worst[0]


@pytest.mark.slow
def test_the_report_holds_bounded_summaries_of_any_number_of_events() -> None:
    from analyzer.protocol.types import TOPIC_COMMAND, TOPIC_GIMBAL_ATTITUDE, Event
    from analyzer.report.collect import MAX_MARKS, MAX_TARGETS, ReportData

    data = ReportData()
    rng = random.Random(7)
    for i in range(100_000):
        t = 1_700_000_000.0 + i * 0.01
        attitude = {"pitch_deg": rng.uniform(-90, 30), "yaw_deg": 0.0, "motor_yaw_deg": 0.0}
        data.add(Event(TOPIC_GIMBAL_ATTITUDE, t, "sim", attitude))
        data.add(Event(TOPIC_COMMAND, t, "sim", {"name": "specified_angle", "pitch_deg": -i}))
        verdict = rng.choice(["obeyed", "not_obeyed"])
        data.add_finding(
            finding("specified_angle", "target", verdict, t, target_deg=-i % 90, axis="pitch")
        )
    assert data.findings.total == 100_000  # counted exactly ...
    (group,) = data.findings.groups.values()
    assert len(group.examples()) == data.findings.keep  # ... but a few kept
    assert len(data.attitude.buckets) <= data.attitude.limit
    assert len(data.marks.rows()) <= MAX_MARKS
    assert all(len(s.buckets) <= MAX_TARGETS for s in data.targets.values())
    assert len(data.target_rows()) <= 2 * 2 * MAX_TARGETS  # two verdicts, extremes per bucket
    pitches = [r[1] for r in data.attitude.rows()]
    assert min(pitches) >= -90 and max(pitches) <= 30
