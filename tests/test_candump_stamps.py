"""The scan's timestamps are exactly the floats the line parser makes of the same text."""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from analyzer.inputs.candump.reader import CandumpParser
from analyzer.inputs.candump.scan import stamp_times
from analyzer.protocol.types import CanFrame

# candump -L writes ``(%010lu.%06lu)``; the line parser takes up to 15 digits before the point.
SECONDS = st.integers(0, 10**15 - 1)
MICROS = st.integers(0, 999_999)


@given(st.lists(st.tuples(SECONDS, MICROS), max_size=20))
def test_stamp_times_equal_float_of_the_text(stamps: list[tuple[int, int]]) -> None:
    texts = [b"%d.%06d" % (s, us) for s, us in stamps]
    assert stamp_times(texts) == [float(t) for t in texts]


@given(SECONDS, MICROS, st.sampled_from([b"%d.%06d", b"%010d.%06d"]))
def test_a_scanned_frame_has_the_time_the_line_parser_gives(
    seconds: int, micros: int, layout: bytes
) -> None:
    line = b"(" + layout % (seconds, micros) + b") can0 00000F01#0F04E8030CFE0000\n"
    scanned = CandumpParser("t.log", wanted_ids={0xF01}).parse_block(line * 3)
    parsed = CandumpParser("t.log", wanted_ids={0xF01}, scan=False).parse_block(line * 3)
    assert scanned == parsed
    assert isinstance(scanned[0], CanFrame)
    assert scanned[0].time == float(layout % (seconds, micros))


def test_other_stamp_widths_go_to_the_line_parser_with_the_same_result() -> None:
    text = b"".join(
        b"(%s) can0 00000F01#0F04E8030CFE0000\n" % stamp
        for stamp in (b"1715680800.5", b"1715680800.123", b"1715680800.1234567", b"0.000001")
    )
    scanned = CandumpParser("t.log", wanted_ids={0xF01}).parse_block(text)
    parsed = CandumpParser("t.log", wanted_ids={0xF01}, scan=False).parse_block(text)
    assert scanned == parsed
    assert [f.time for f in scanned if isinstance(f, CanFrame)] == [
        1715680800.5,
        1715680800.123,
        1715680800.1234567,
        0.000001,
    ]
