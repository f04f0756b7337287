"""The C-speed scan of candump -L blocks gives exactly what the line parser gives, line by line."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings

from analyzer.inputs.candump.scan import id_texts, scanner
from analyzer.protocol.ids import PROTOCOL_IDS
from analyzer.protocol.types import CanFrame, Event
from tests.candump_texts import CUTS, TEXTS, WANTED_SETS, parse, summary


@pytest.mark.slow
@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(TEXTS, CUTS, WANTED_SETS)
def test_scan_and_line_parser_agree_on_any_text(
    text: bytes, cuts: list[int], wanted: frozenset[int] | None
) -> None:
    fast = parse(text, cuts, wanted_ids=wanted)
    slow = parse(text, [], wanted_ids=wanted, scan=False)
    assert summary(*fast) == summary(*slow)


def test_scan_takes_a_busy_log_in_one_pass_and_counts_every_line() -> None:
    foreign = b"(1715680800.%06d) can0 18F00000#0011223344556677\n"
    wanted = b"(1715680800.%06d) can0 00000F01#0F0700000000C800 R\n"
    text = b"".join((wanted if i % 10 == 3 else foreign) % i for i in range(1000))
    items, parser = parse(text, [], wanted_ids=PROTOCOL_IDS)
    frames = [i for i in items if isinstance(i, CanFrame)]
    assert len(frames) == 100 and all(f.direction == "rx" for f in frames)
    assert frames[0] == CanFrame(
        1715680800.000003, 0xF01, bytes.fromhex("0F0700000000C800"), True, "can0", direction="rx"
    )
    assert parser.stats == {
        "lines": 1000,
        "frames": 1000,
        "other_frames": 900,
        "bad_lines": 0,
        "blank_lines": 0,
        "note_lines": 0,
    }
    assert (parser.first_time, parser.last_time) == (1715680800.0, 1715680800.000999)


def test_a_bad_line_in_a_run_is_reported_with_its_line_number() -> None:
    good = b"(1.000000) can0 18F00000#00\n"
    text = good * 5 + b"(1.000001) can0 18F00000#0G\n" + good * 5
    items, parser = parse(text, [], wanted_ids=PROTOCOL_IDS)
    (bad,) = items
    assert isinstance(bad, Event) and bad.fields["line"] == 6
    assert "not hex" in bad.fields["detail"]
    assert parser.stats["frames"] == 10 and parser.stats["bad_lines"] == 1


@pytest.mark.parametrize("wanted", [PROTOCOL_IDS, None])
def test_scanner_is_made_once_per_set_of_ids(wanted: frozenset[int] | None) -> None:
    assert scanner(wanted) is scanner(wanted)


def test_id_texts_cover_both_widths_of_small_ids() -> None:
    assert id_texts({0xF01, 0x030F0001, 0x2FFFFFFF}) == ["00000F01", "F01", "030F0001"]
