"""The fleet tables' Arrow arrays are made from numpy buffers, and are what ``pa.array`` makes.

``table`` never calls ``pa.array`` (pyarrow would import pandas for it): the values of
decoded events become numpy buffers and Arrow arrays by our own rules, checked here
against ``pa.array`` itself on values of every type (and against the values a column
cannot take: both refuse them). The column builders keep a table's rows from block to
block and hand out row groups: any sequence of appends and takes gives the rows that
went in, in order. A value of another type than its column is kept in ``extra``.
"""

from __future__ import annotations

import json
import math
from typing import Any

import pyarrow as pa
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from analyzer.fleet.arrow_arrays import BOOL, FLOAT, INT, STRING, STRINGS, column, repeated
from analyzer.fleet.column_builders import builder
from analyzer.fleet.column_sink import CollectedTables, ColumnSink
from analyzer.fleet.columns import TIME
from analyzer.pipeline import Batch
from analyzer.protocol.types import TOPIC_GIMBAL_ATTITUDE, Event

KINDS = [STRING, INT, FLOAT, BOOL, STRINGS, TIME]
REFUSED = (pa.ArrowInvalid, pa.ArrowTypeError, TypeError, ValueError, OverflowError)

texts = st.text(max_size=6)
scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(2**64), max_value=2**64),
    st.integers(min_value=-1000, max_value=1000),
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(min_value=-1e6, max_value=1e6),
    texts,
    st.binary(max_size=4),
)
text_lists = st.one_of(
    st.lists(st.one_of(st.none(), texts, st.binary(max_size=3)), max_size=3),
    st.tuples(texts),
)
# What one column of a block holds: values of the column's type with nulls among them
# (the usual), or anything at all.
TYPICAL = {
    STRING: st.one_of(st.none(), texts),
    INT: st.one_of(st.none(), st.integers(min_value=-(2**63), max_value=2**63 - 1)),
    FLOAT: st.one_of(st.none(), st.floats()),
    BOOL: st.one_of(st.none(), st.booleans()),
    STRINGS: st.one_of(st.none(), st.lists(st.one_of(st.none(), texts), max_size=3)),
    TIME: st.one_of(st.none(), st.integers(min_value=-(2**62), max_value=2**62)),
}


def values_for(kind: pa.DataType) -> st.SearchStrategy[list[Any]]:
    """A column's values: of its type (nulls among them), or anything at all (not text in
    a list column: pyarrow makes a list of its characters, ``column`` refuses it)."""
    odd = st.one_of(scalars, text_lists)
    if kind == STRINGS:
        odd = st.one_of(text_lists, st.none(), st.booleans(), st.integers(), st.floats())
    return st.lists(TYPICAL[kind], max_size=40) | st.lists(
        st.one_of(TYPICAL[kind], odd), max_size=12
    )


def made(values: list[Any], kind: pa.DataType) -> tuple[str, Any]:
    """What ``column`` does with ``values``: the array's type, nulls and values (NaN as
    text, so that it equals itself), or "refused"."""
    try:
        array = column(list(values), kind)
    except REFUSED:
        return ("refused", None)
    array.validate(full=True)
    return _seen(array)


def by_pyarrow(values: list[Any], kind: pa.DataType) -> tuple[str, Any]:
    try:
        array = pa.array(list(values), kind)
    except REFUSED:
        return ("refused", None)
    return _seen(array)


def _seen(array: pa.Array) -> tuple[str, Any]:
    # timestamps as their microseconds: Python's datetime ends at the year 9999
    plain = array.view(pa.int64()) if array.type == TIME else array
    shown = [_plain(v) for v in plain.to_pylist()]
    return (str(array.type), (array.null_count, shown))


def _plain(value: Any) -> Any:
    if isinstance(value, float) and math.isnan(value):
        return "nan"
    return value


@pytest.mark.parametrize("kind", KINDS, ids=str)
@settings(max_examples=200, deadline=None)
@given(data=st.data())
def test_a_column_is_what_pa_array_makes_of_the_same_values(
    kind: pa.DataType, data: st.DataObject
) -> None:
    values = data.draw(values_for(kind))
    assert made(values, kind) == by_pyarrow(values, kind)


def test_what_pyarrow_does_with_odd_values_is_kept() -> None:
    """pyarrow truncates a float in an int64 column, takes a bool as 1.0 in a float64
    one but refuses it in an int64 one, and an integer a double cannot hold exactly."""
    assert column([1.9, -1.9, None], INT).to_pylist() == [1, -1, None]
    assert column([True, 2, 0.5], FLOAT).to_pylist() == [1.0, 2.0, 0.5]
    for values, kind in (([True], INT), ([2**53 + 1], FLOAT), (["1"], FLOAT), ([1], BOOL)):
        with pytest.raises(REFUSED):
            column(values, kind)
    assert column([b"ab", "\u00e9"], STRING).to_pylist() == ["ab", "\u00e9"]
    assert repeated("r\u00e9c", 3).to_pylist() == ["r\u00e9c"] * 3


operations = st.lists(
    st.one_of(
        st.tuples(st.just("append"), st.integers(0, 30)),
        st.tuples(st.just("nulls"), st.integers(0, 30)),
        st.tuples(st.just("take"), st.integers(0, 40)),
    ),
    max_size=25,
)


@pytest.mark.parametrize("kind", KINDS, ids=str)
@settings(max_examples=80, deadline=None)
@given(data=st.data(), steps=operations)
def test_a_builder_gives_back_its_rows_in_order_whatever_the_appends_and_takes(
    kind: pa.DataType, data: st.DataObject, steps: list[tuple[str, int]]
) -> None:
    rows = builder(kind)
    held: list[Any] = []
    for what, count in steps:
        if what == "append":
            values = data.draw(st.lists(TYPICAL[kind], min_size=count, max_size=count))
            rows.append(list(values))
            held += values
        elif what == "nulls":
            rows.append_nulls(count)
            held += [None] * count
        else:
            count = min(count, len(held))
            taken = rows.take(count)  # good until the next append or take: read now
            taken.validate(full=True)
            assert _seen(taken) == by_pyarrow(held[:count], kind)
            del held[:count]
        assert rows.size - getattr(rows, "taken", 0) == len(held)


def test_a_refused_value_adds_nothing_to_a_builder() -> None:
    rows = builder(INT)
    rows.append([1, 2])
    with pytest.raises(REFUSED):
        rows.append([3, "four"])
    assert rows.take(2).to_pylist() == [1, 2] and rows.take(0).to_pylist() == []


def test_a_value_of_another_type_than_its_column_is_kept_in_extra() -> None:
    kept = CollectedTables()
    sink = ColumnSink(kept, "r", "h", group_rows=3)
    fields: list[dict[str, Any]] = [
        {"pitch_deg": 1.5, "gimbal_type_code": 2, "tracking": True},
        {"pitch_deg": "high", "gimbal_type_code": True, "tracking": 1, "colour": "red"},
        {"pitch_deg": 7, "gimbal_type_code": 3, "tracking": None},
        {"pitch_deg": None, "gimbal_type": ["a"], "crc_set": False},
    ]
    events = [Event(TOPIC_GIMBAL_ATTITUDE, 1.7e9 + n, "can0", f) for n, f in enumerate(fields)]
    sink.handle(Batch(events=events))
    sink.close()
    table = kept.tables()["attitude"]
    assert table.num_rows == 4 and sink.rows == 4
    got = table.select(["pitch_deg", "gimbal_type_code", "tracking", "gimbal_type"]).to_pylist()
    assert got == [
        {"pitch_deg": 1.5, "gimbal_type_code": 2, "tracking": True, "gimbal_type": None},
        {"pitch_deg": None, "gimbal_type_code": None, "tracking": None, "gimbal_type": None},
        {"pitch_deg": 7.0, "gimbal_type_code": 3, "tracking": None, "gimbal_type": None},
        {"pitch_deg": None, "gimbal_type_code": None, "tracking": None, "gimbal_type": None},
    ]
    extra = [None if e is None else json.loads(e) for e in table.column("extra").to_pylist()]
    assert extra == [
        None,
        {"colour": "red", "pitch_deg": "high", "gimbal_type_code": True, "tracking": 1},
        None,
        {"gimbal_type": ["a"]},
    ]
