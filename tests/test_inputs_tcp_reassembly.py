"""TCP reassembly: order, retransmissions, overlaps, wrap-around, lost segments, properties."""

from __future__ import annotations

import itertools
import random

from hypothesis import given, settings
from hypothesis import strategies as st

from analyzer.inputs.pcap.tcp_reassembly import Delivered, Gap, Result, TcpDirection

ISN = 1000


def delivered(results: list[Result]) -> bytes:
    return b"".join(r.data for r in results if isinstance(r, Delivered))


def accounted(state: TcpDirection) -> bool:
    return state.bytes_in == (
        state.bytes_delivered
        + state.bytes_duplicate
        + state.bytes_out_of_window
        + state.bytes_pending
    )


def test_in_order_after_syn() -> None:
    state = TcpDirection()
    out = state.segment(ISN, b"", 0.0, syn=True)
    out += state.segment(ISN + 1, b"hello ", 0.1)
    out += state.segment(ISN + 7, b"world", 0.2)
    assert delivered(out) == b"hello world"
    assert [r.offset for r in out if isinstance(r, Delivered)] == [0, 6]
    assert accounted(state)


def test_out_of_order_waits_for_the_hole() -> None:
    state = TcpDirection()
    state.segment(ISN, b"", 0.0, syn=True)
    assert state.segment(ISN + 7, b"world", 0.1) == []
    out = state.segment(ISN + 1, b"hello ", 0.2)
    assert delivered(out) == b"hello world"
    assert all(r.time == 0.2 for r in out)
    assert accounted(state)


def test_retransmissions_and_overlaps_deliver_once() -> None:
    state = TcpDirection()
    state.segment(ISN, b"", 0.0, syn=True)
    out = state.segment(ISN + 1, b"abcdef", 0.1)
    out += state.segment(ISN + 1, b"abcdef", 0.2)  # retransmitted
    out += state.segment(ISN + 4, b"defghi", 0.3)  # overlaps the end
    out += state.segment(ISN + 13, b"mno", 0.4)  # ahead
    out += state.segment(ISN + 10, b"jklm", 0.5)  # fills the hole, overlaps the held one
    out += state.segment(ISN + 2, b"XX", 0.6)  # old and different: the first copy wins
    assert delivered(out) == b"abcdefghijklmno"
    assert state.bytes_duplicate == 6 + 3 + 1 + 2
    assert accounted(state)


def test_sequence_numbers_wrap_around() -> None:
    state = TcpDirection()
    isn = (1 << 32) - 4
    state.segment(isn, b"", 0.0, syn=True)
    out = state.segment(isn + 1, b"abc", 0.1)
    out += state.segment((isn + 4) % (1 << 32), b"defg", 0.2)
    assert delivered(out) == b"abcdefg"


def test_capture_starting_mid_connection() -> None:
    state = TcpDirection()
    out = state.segment(555, b"abc", 0.0)
    out += state.segment(558, b"def", 0.1)
    assert delivered(out) == b"abcdef"


def test_lost_segment_is_reported_at_flush() -> None:
    state = TcpDirection()
    state.segment(ISN, b"", 0.0, syn=True)
    out = state.segment(ISN + 1, b"abc", 0.1)
    out += state.segment(ISN + 10, b"xyz", 0.2)
    out += state.flush(0.3)
    gaps = [r for r in out if isinstance(r, Gap)]
    assert gaps == [Gap(0.3, 3, 6)]
    assert delivered(out) == b"abcxyz"
    assert state.bytes_missing == 6 and state.gaps == 1
    assert accounted(state)


def test_hole_given_up_after_waiting_too_long() -> None:
    state = TcpDirection(max_wait=1.0)
    state.segment(ISN, b"", 0.0, syn=True)
    assert state.segment(ISN + 5, b"late", 0.0) == []
    out = state.segment(ISN + 9, b"!", 2.0)
    assert [type(r) for r in out] == [Gap, Delivered, Delivered]
    assert delivered(out) == b"late!"


def test_hole_given_up_when_too_much_waits() -> None:
    state = TcpDirection(max_pending=10)
    state.segment(ISN, b"", 0.0, syn=True)
    state.segment(ISN + 2, b"0123456", 0.0)
    out = state.segment(ISN + 9, b"789ab", 0.0)
    assert isinstance(out[0], Gap) and out[0].size == 1
    assert delivered(out) == b"0123456789ab"


def test_far_away_segment_is_out_of_window() -> None:
    state = TcpDirection()
    state.segment(ISN, b"", 0.0, syn=True)
    assert state.segment(ISN + 1 + (1 << 30), b"stray", 0.0) == []
    assert state.bytes_out_of_window == 5
    assert accounted(state)


def test_data_before_the_syn_is_out_of_window_not_a_retransmission() -> None:
    """No byte of a connection precedes its SYN: a damaged SYN (a bit of its sequence
    number flipped) leaves the data before it, which must not pass for old data."""
    state = TcpDirection()
    state.segment(ISN + (1 << 24), b"", 0.0, syn=True)
    assert state.segment(ISN + 1, b"hello", 0.1) == []
    assert state.bytes_out_of_window == 5 and state.bytes_duplicate == 0
    assert accounted(state)
    mid_way = TcpDirection()  # the capture began mid-connection: older data is a repeat
    mid_way.segment(ISN + 100, b"later", 0.0)
    mid_way.segment(ISN, b"older", 0.1)
    assert mid_way.bytes_duplicate == 5 and mid_way.bytes_out_of_window == 0


# -- properties ------------------------------------------------------------------------------


@st.composite
def segmented(draw: st.DrawFn) -> tuple[bytes, int, list[tuple[int, int]]]:
    """A stream, an ISN and segments (start, end) covering it, some repeated or overlapping."""
    stream = draw(st.binary(min_size=1, max_size=300))
    isn = draw(st.integers(0, (1 << 32) - 1))
    cuts = sorted(set(draw(st.lists(st.integers(1, len(stream) - 1 or 1), max_size=20))))
    bounds = [0, *[c for c in cuts if c < len(stream)], len(stream)]
    segments = list(itertools.pairwise(bounds))
    extra = draw(
        st.lists(
            st.tuples(st.integers(0, len(stream) - 1), st.integers(1, 40)).map(
                lambda t: (t[0], min(len(stream), t[0] + t[1]))
            ),
            max_size=8,
        )
    )
    return stream, isn, segments + extra


@settings(max_examples=300)
@given(segmented(), st.randoms(use_true_random=False))
def test_any_order_with_repeats_gives_the_stream(
    case: tuple[bytes, int, list[tuple[int, int]]], rnd: random.Random
) -> None:
    stream, isn, segments = case
    rnd.shuffle(segments)
    state = TcpDirection()
    out = state.segment(isn, b"", 0.0, syn=True)
    for start, end in segments:
        out += state.segment((isn + 1 + start) % (1 << 32), stream[start:end], 0.0)
        assert accounted(state)
    out += state.flush(1.0)
    assert delivered(out) == stream
    assert state.bytes_missing == 0
    assert accounted(state)


@settings(max_examples=300)
@given(segmented(), st.randoms(use_true_random=False), st.data())
def test_dropped_segments_become_gaps_of_the_right_size(
    case: tuple[bytes, int, list[tuple[int, int]]], rnd: random.Random, data: st.DataObject
) -> None:
    stream, isn, segments = case
    kept = [s for s in segments if data.draw(st.booleans())]
    rnd.shuffle(kept)
    state = TcpDirection()
    out = state.segment(isn, b"", 0.0, syn=True)
    for start, end in kept:
        out += state.segment((isn + 1 + start) % (1 << 32), stream[start:end], 0.0)
    out += state.flush(1.0)
    covered = bytearray(len(stream))
    for start, end in kept:
        covered[start:end] = b"\1" * (end - start)
    last = max((end for _, end in kept), default=0)
    expected = bytes(b for b, c in zip(stream, covered, strict=True) if c)
    assert delivered(out) == expected
    assert state.bytes_missing == sum(1 for c in covered[:last] if not c)
    assert accounted(state)


@settings(max_examples=300)
@given(
    st.lists(
        st.tuples(st.integers(0, (1 << 32) - 1), st.binary(max_size=30), st.booleans()),
        max_size=25,
    )
)
def test_arbitrary_segments_never_raise(segments: list[tuple[int, bytes, bool]]) -> None:
    state = TcpDirection(max_pending=64)
    out: list[Result] = []
    for i, (seq, payload, syn) in enumerate(segments):
        out += state.segment(seq, payload, float(i), syn=syn)
        assert accounted(state)
    out += state.flush(99.0)
    assert state.bytes_pending == 0
    assert len(delivered(out)) == state.bytes_delivered
