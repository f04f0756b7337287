"""The fleet's standard questions, each described once: which rows, grouped how, counted how.

A description is data, not SQL: ``queries`` renders it to DuckDB SQL (the laptop path) and
``dask_questions`` to dask.dataframe operations that run on a cluster's workers. Both end
in the same finishing step (``finish_sql``: rates, rounding, order, limit), run by DuckDB
over the few aggregated rows, so the two paths give the same answers to the last digit.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

from analyzer.fleet.columns import RECORDINGS

WORST = 10  # flights in the worst-flights list
CRC_ALARM = 0.01  # a CRC error rate above this is a reason to look at a flight
JOINED = "_j_"  # prefix of the columns a question takes from the table it joins


@dataclass(frozen=True)
class Column:
    """A column of the question's table, or (``joined``) of the table joined to it."""

    name: str
    joined: bool = False

    @property
    def source(self) -> str:
        """Its name among the question's source rows."""
        return JOINED + self.name if self.joined else self.name


@dataclass(frozen=True)
class Constant:
    """The same value for every row (the one group of a fleet without tags)."""

    value: str


@dataclass(frozen=True)
class IsoWeek:
    """The ISO week of a UTC time, as ``2023-W46`` (null for a null time)."""

    column: Column


@dataclass(frozen=True)
class Key:
    """A group key: its name in the answer and what it is."""

    name: str
    expr: Column | Constant | IsoWeek


@dataclass(frozen=True)
class Where:
    """A row filter: ``null``, ``not_null``, ``equal`` or ``not_equal`` (null never equal)."""

    column: Column
    test: Literal["null", "not_null", "equal", "not_equal"]
    value: str | None = None


AggFunc = Literal["count", "count_equal", "sum", "min", "max", "median"]


@dataclass(frozen=True)
class Aggregate:
    """One aggregate of a group: ``count`` (rows, or non-null values of ``column``),
    ``count_equal`` (rows whose ``column`` is ``value``), ``sum`` (of ``column``, plus
    ``plus`` row by row when given), ``min``, ``max``, ``median``. As in SQL, a sum, min,
    max or median of no values is null."""

    name: str
    func: AggFunc
    column: Column | None = None
    plus: Column | None = None
    value: str | None = None


@dataclass(frozen=True)
class Output:
    """A column of the answer: a key or aggregate (``of``), divided by ``over`` (a rate,
    null when ``over`` is 0), rounded to ``digits``."""

    name: str
    of: str
    over: str | None = None
    digits: int | None = None


@dataclass(frozen=True)
class Order:
    name: str
    descending: bool = False


@dataclass(frozen=True)
class Join:
    """Each row of the question's table joined (inner) with the row of ``table`` that has
    the same ``on``, for these ``columns``."""

    table: str
    on: str
    columns: tuple[str, ...]


@dataclass(frozen=True)
class GroupQuestion:
    """Rows of ``table`` (joined, filtered), grouped by ``keys``, aggregated, then finished."""

    name: str
    title: str
    table: str
    keys: tuple[Key, ...]
    aggregates: tuple[Aggregate, ...]
    outputs: tuple[Output, ...]
    order: tuple[Order, ...] = ()
    where: tuple[Where, ...] = ()
    join: Join | None = None
    limit: int | None = None

    def columns(self) -> tuple[list[str], list[str]]:
        """The columns read from the table and from the joined table (without the key)."""
        used: list[Column] = [w.column for w in self.where]
        for key in self.keys:
            if isinstance(key.expr, Column):
                used.append(key.expr)
            elif isinstance(key.expr, IsoWeek):
                used.append(key.expr.column)
        for agg in self.aggregates:
            used += [c for c in (agg.column, agg.plus) if c is not None]
        main = _unique([c.name for c in used if not c.joined])
        joined = _unique([c.name for c in used if c.joined])
        if self.join is not None and self.join.on not in main:
            main.append(self.join.on)
        return main, joined


@dataclass(frozen=True)
class Term:
    """A part of a flight's score: ``weight`` times the column (``present``: 1 when the
    column is not null), less ``minus`` when given; null counts as 0."""

    column: str
    weight: int
    present: bool = False
    minus: str | None = None


@dataclass(frozen=True)
class Reason:
    """A words-for-people part of a worst flight's reason, in SQL over its row (``r``):
    it runs over the few flights in the answer only, the same way on both paths."""

    when: str
    text: str


@dataclass(frozen=True)
class TopQuestion:
    """The rows of ``table`` with the highest score above 0 (ties by ``tie``), at most
    ``limit``, shown with ``shown`` columns, the score and the reason."""

    name: str
    title: str
    table: str
    shown: tuple[str, ...]
    score: tuple[Term, ...]
    reasons: tuple[Reason, ...]
    reads: tuple[str, ...]  # the columns the reasons read
    tie: str = "recording"
    limit: int = WORST

    def columns(self) -> list[str]:
        terms = [c for t in self.score for c in (t.column, t.minus) if c is not None]
        return _unique([*self.shown, self.tie, *terms, *self.reads])


Question = GroupQuestion | TopQuestion


def _unique(names: Sequence[str]) -> list[str]:
    return list(dict.fromkeys(names))


def _link(name: str, title: str, keys: tuple[Key, ...]) -> GroupQuestion:
    """CRC error rate and feedback gaps of the readable recordings per ``keys``."""
    c = Column
    return GroupQuestion(
        name=name,
        title=title,
        table=RECORDINGS,
        where=(Where(c("error"), "null"),),
        keys=keys,
        aggregates=(
            Aggregate("flights", "count"),
            Aggregate("crc_errors", "sum", c("crc_errors")),
            Aggregate("crc_protected", "sum", c("crc_checked"), plus=c("crc_errors")),
            Aggregate("gaps", "sum", c("gaps")),
            Aggregate("longest_gap_s", "max", c("longest_gap_s")),
        ),
        outputs=(
            *(Output(k.name, k.name) for k in keys),
            Output("flights", "flights"),
            Output("crc_errors", "crc_errors"),
            Output("crc_protected", "crc_protected"),
            Output("crc_error_rate", "crc_errors", over="crc_protected", digits=6),
            Output("gaps", "gaps"),
            Output("longest_gap_s", "longest_gap_s", digits=3),
        ),
        order=(
            (Order("crc_error_rate", descending=True), *(Order(k.name) for k in keys))
            if len(keys) == 1
            else tuple(Order(k.name) for k in keys)
        ),
    )


def _judged(
    name: str,
    title: str,
    by: str,
    tag: str,
    key: Column | Constant,
    where: tuple[Where, ...],
    figures: tuple[tuple[Aggregate, Output], ...],
    counted: str = "findings",
) -> GroupQuestion:
    """Findings (``where``) counted per ``by`` and tag: how many (``counted``), by
    verdict, then the ``figures`` (an aggregate and its output each)."""
    findings = Column
    verdicts = ("obeyed", "partial", "not_obeyed", "unknown")
    return GroupQuestion(
        name=name,
        title=title,
        table="findings",
        join=Join(RECORDINGS, "content_hash", (key.name,)) if isinstance(key, Column) else None,
        where=where,
        keys=(Key(by, findings(by)), Key(tag, key)),
        aggregates=(
            Aggregate(counted, "count"),
            *(Aggregate(v, "count_equal", findings("verdict"), value=v) for v in verdicts),
            *(aggregate for aggregate, _ in figures),
        ),
        outputs=(
            Output(by, by),
            Output(tag, tag),
            Output(counted, counted),
            *(Output(v, v) for v in verdicts),
            *(output for _, output in figures),
        ),
        order=(Order(by), Order(tag)),
    )


def _median(field: str) -> tuple[Aggregate, Output]:
    name = f"median_{field}"
    return Aggregate(name, "median", Column(field)), Output(name, name, digits=3)


def _obedience(tag: str, key: Column | Constant) -> GroupQuestion:
    return _judged(
        f"obedience_by_{tag}",
        f"Obedience per command and {tag}",
        "command",
        tag,
        key,
        (Where(Column("command"), "not_equal", "feedback"),),
        (_median("response_s"),),
    )


def _sticks(tag: str, key: Column | Constant) -> GroupQuestion:
    """The stick movements (gimbal_control streams) per component and tag: how many (one
    finding each), how they were judged, the measured over commanded motion, the lag and
    the cadence."""
    longest = (
        Aggregate("longest_interval_s", "max", Column("interval_max_s")),
        Output("longest_interval_s", "longest_interval_s", digits=3),
    )
    return _judged(
        f"sticks_by_{tag}",
        f"Stick movements per component and {tag}",
        "component",
        tag,
        key,
        (
            Where(Column("command"), "equal", "gimbal_control"),
            Where(Column("check"), "equal", "rate"),
        ),
        (*(_median(m) for m in ("pan_ratio", "tilt_ratio", "lag_s", "interval_mean_s")), longest),
        "movements",
    )


def standard_questions(tags: Sequence[str]) -> list[Question]:
    """CRC and gaps per tag and per week, obedience per command and tag, stick movements
    per component and tag, the worst flights (one group, ``fleet``, when the dataset has
    no tags)."""
    groups: list[tuple[str, Column | Constant]] = [(t, Column(t)) for t in tags] or [
        ("fleet", Constant("all"))
    ]
    questions: list[Question] = []
    for tag, expr in groups:
        title = f"CRC error rate and feedback gaps per {tag}"
        questions.append(_link(f"link_by_{tag}", title, (Key(tag, expr),)))
    for tag, expr in groups:
        week = Key("week", IsoWeek(Column("start")))
        questions.append(
            _link(
                f"link_by_week_{tag}",
                f"CRC error rate and feedback gaps per week and {tag}",
                (week, Key(tag, expr)),
            )
        )
    for tag, expr in groups:
        joined = Column(expr.name, joined=True) if isinstance(expr, Column) else expr
        questions.append(_obedience(tag, joined))
    for tag, expr in groups:
        joined = Column(expr.name, joined=True) if isinstance(expr, Column) else expr
        questions.append(_sticks(tag, joined))
    questions.append(worst_flights(tags))
    return questions


def worst_flights(tags: Sequence[str]) -> TopQuestion:
    return TopQuestion(
        name="worst_flights",
        title=f"The worst flights (at most {WORST})",
        table=RECORDINGS,
        shown=("recording", *tags, "start"),
        score=(
            Term("error", 1000, present=True),
            Term("crc_error_rate", 1000),
            Term("findings_not_obeyed", 10),  # commands only: a gap is its own term
            Term("findings_partial", 3),
            Term("gaps", 5),
            Term("diagnostics", 1, minus="crc_errors"),
        ),
        reasons=(
            Reason("r.error IS NOT NULL", "'unreadable: ' || r.error"),
            Reason(
                f"r.crc_error_rate > {CRC_ALARM}",
                "'CRC error rate ' || round(r.crc_error_rate, 4)",
            ),
            Reason(
                "r.findings_not_obeyed > 0",
                "r.findings_not_obeyed || ' finding(s) not obeyed'",
            ),
            Reason("r.findings_partial > 0", "r.findings_partial || ' partial'"),
            Reason(
                "r.gaps > 0",
                "r.gaps || ' feedback gap(s), longest ' || round(r.longest_gap_s, 1) || ' s'",
            ),
            Reason(
                "r.diagnostics > r.crc_errors",
                "(r.diagnostics - r.crc_errors) || ' other diagnostic(s)'",
            ),
        ),
        reads=(
            *("error", "crc_error_rate", "findings_not_obeyed", "findings_partial"),
            *("gaps", "longest_gap_s", "diagnostics", "crc_errors"),
        ),
    )


def overview() -> GroupQuestion:
    """The fleet report's overview: recordings, unreadable ones, frames, findings, time range."""
    c = Column
    return GroupQuestion(
        name="overview",
        title="Overview",
        table=RECORDINGS,
        keys=(Key("fleet", Constant("all")),),
        aggregates=(
            Aggregate("recordings", "count"),
            Aggregate("failed", "count", c("error")),
            Aggregate("frames", "sum", c("frames")),
            Aggregate("findings", "sum", c("findings")),
            Aggregate("first", "min", c("start")),
            Aggregate("last", "max", c("end")),
        ),
        outputs=tuple(
            Output(n, n) for n in ("recordings", "failed", "frames", "findings", "first", "last")
        ),
    )
