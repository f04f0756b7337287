"""candump screen output with every -t mode: -ta, -tz, -td (added up, like asc2log), -tA."""

from __future__ import annotations

import datetime
import io
import itertools
import json
import random
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from analyzer.cli import main
from analyzer.inputs import open_input
from analyzer.inputs.base import ABSOLUTE, DELTA, RELATIVE_TO_START
from analyzer.inputs.candump.reader import DECIDE_AFTER
from analyzer.inputs.stdin import StdinCandumpReader
from analyzer.protocol.codec import encode_command
from analyzer.protocol.types import CanFrame

T0 = 1_715_680_800.0
DATA = " ".join(f"{b:02X}" for b in encode_command("look_down"))


def screen(stamps: list[str]) -> str:
    """``candump -t? can0``: the stamp in brackets, the interface, ID, [len] and data bytes
    (the layout of can-utils' candump: ' (stamp)  can0  00000F01   [8]  EB 90 ...')."""
    return "".join(f" ({s})  can0  00000F01   [8]  {DATA}\n" for s in stamps)


def flight_times(count: int = 41, seed: int = 7) -> list[float]:
    """Capture times of a 2 s stretch with jitter: a command about every 50 ms."""
    rng = random.Random(seed)
    times, t = [], 0.0
    for _ in range(count):
        times.append(round(t, 6))
        t += 0.05 + rng.uniform(-0.004, 0.004)
    return times


def frames_of(text: str, tmp_path: Path) -> tuple[list[CanFrame], str | None]:
    path = tmp_path / "screen.log"
    path.write_text(text, encoding="utf-8")
    with open_input(str(path)) as reader:
        frames = [i for i in reader if isinstance(i, CanFrame)]
        return frames, reader.time_base


def test_delta_times_are_added_up(tmp_path: Path) -> None:
    times = flight_times()
    deltas = [0.0] + [b - a for a, b in itertools.pairwise(times)]
    frames, base = frames_of(screen([f"{d:010.6f}"[-10:] for d in deltas]), tmp_path)
    assert base == DELTA
    assert [f.time for f in frames] == pytest.approx(times, abs=2e-6 * len(times))
    assert frames[-1].time - frames[0].time == pytest.approx(2.0, abs=0.1)  # 2 s, not 0.1 s


def test_steady_delta_times_are_recognised(tmp_path: Path) -> None:
    frames, base = frames_of(screen(["000.000000"] + ["000.100000"] * 20), tmp_path)
    assert base == DELTA
    assert frames[-1].time == pytest.approx(2.0)


def test_relative_to_start_times_stay(tmp_path: Path) -> None:
    times = flight_times()
    frames, base = frames_of(screen([f"{t:010.6f}" for t in times]), tmp_path)
    assert base == RELATIVE_TO_START
    assert [f.time for f in frames] == pytest.approx(times)


def test_absolute_and_dated_times_keep_working(tmp_path: Path) -> None:
    frames, base = frames_of(screen([f"{T0 + t:.6f}" for t in flight_times()]), tmp_path)
    assert base == ABSOLUTE and frames[0].time == T0
    start = datetime.datetime(2024, 5, 14, 10, 0, 0)
    dated = [(start + datetime.timedelta(seconds=t)).isoformat(" ") for t in flight_times()]
    frames, base = frames_of(screen([d if "." in d else d + ".000000" for d in dated]), tmp_path)
    assert base == ABSOLUTE and frames[0].time == start.timestamp()


def test_delta_times_from_a_pipe_are_added_up_too() -> None:
    deltas = ["000.000000"] + ["000.250000", "000.150000"] * 4
    reader = StdinCandumpReader(io.BytesIO(screen(deltas).encode()))
    frames = [i for i in reader if isinstance(i, CanFrame)]
    assert [f.time for f in frames] == pytest.approx(
        [0.0, 0.25, 0.4, 0.65, 0.8, 1.05, 1.2, 1.45, 1.6]
    )
    assert reader.time_base == DELTA


def test_summary_names_the_time_base(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "td.log"
    path.write_text(screen(["000.000000"] + ["000.100000", "000.050000"] * 10), encoding="utf-8")
    assert main(["decode", str(path), "--summary"]) == 0
    out = capsys.readouterr().out
    assert "time base      time since the previous frame (accumulated)" in out
    assert "(1.500 s)" in out
    assert main(["decode", str(path), "--summary", "--json"]) == 0
    obj = json.loads(capsys.readouterr().out)
    assert obj["time_base"] == DELTA and obj["span_s"] == pytest.approx(1.5)


@settings(max_examples=30, deadline=None)
@given(st.lists(st.integers(1, 500_000), min_size=2, max_size=2 * DECIDE_AFTER))
def test_any_delta_sequence_that_varies_adds_up(
    tmp_path_factory: pytest.TempPathFactory, gaps: list[int]
) -> None:
    if len(set(gaps)) == 1 and len(gaps) < 3:
        return  # two equal gaps read the same either way
    stamps = [0, *gaps]
    text = screen([f"{g // 1_000_000:03d}.{g % 1_000_000:06d}" for g in stamps])
    frames, base = frames_of(text, tmp_path_factory.mktemp("td"))
    expected, total = [], 0
    for g in stamps:
        total += g
        expected.append(total / 1e6)
    if base == DELTA:
        assert [f.time for f in frames] == pytest.approx(expected)
    else:  # only a non-decreasing run of deltas can pass for -tz; its times then stand as read
        assert all(b >= a for a, b in itertools.pairwise(stamps))
        assert [f.time for f in frames] == pytest.approx([g / 1e6 for g in stamps])
    assert len(frames) == len(stamps)


# -- a .log that is no candump ---------------------------------------------------------------


def busmaster_log(count: int) -> str:
    """A BusMaster CAN log as BusMaster 3.2 writes it (the layout SavvyCAN's loader reads)."""
    head = [
        "***BUSMASTER Ver 3.2.2***",
        "***PROTOCOL CAN***",
        "***NOTE: PLEASE DO NOT EDIT THIS DOCUMENT***",
        "***[START LOGGING SESSION]***",
        "***START DATE AND TIME 14:5:2024 10:0:0:000***",
        "***HEX***",
        "***SYSTEM MODE***",
        "***START CHANNEL BAUD RATE***",
        "***CHANNEL 1 - Kvaser - Kvaser Leaf Light v2 #0 (Channel 0) - 1000000 bps***",
        "***END CHANNEL BAUD RATE***",
        "***START DATABASE FILES (DBF/DBC)***",
        "***END OF DATABASE FILES (DBF/DBC)***",
        "***<Time><Tx/Rx><Channel><CAN ID><Type><DLC><DataBytes>***",
    ]
    body = [
        f"10:00:{i // 100 % 60:02d}:{i % 100 * 100:04d} Rx 1 0x00000F01 x 8 {DATA}"
        for i in range(count)
    ]
    return "\n".join(head + body + ["***[STOP LOGGING SESSION]***"]) + "\n"


def test_a_busmaster_log_gets_one_note_and_capped_diagnostics(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "bench.log"
    path.write_text(busmaster_log(3000), encoding="utf-8")
    with open_input(str(path)) as reader:
        items = list(reader)
    assert len(items) <= 11  # the first bad lines, then one count
    assert reader.stats["bad_lines"] == 3014
    listed = len(items) - 1
    assert f"{3014 - listed:,} more bad lines not listed" in items[-1].fields["detail"]  # type: ignore[union-attr]
    assert len(reader.notes) == 1 and "BusMaster log" in reader.notes[0]
    assert main(["decode", str(path)]) == 0
    err = capsys.readouterr().err
    assert err.count("is not candump output") == 1  # one note, not one per line


def test_an_asc_file_named_log_says_which_format_to_try(tmp_path: Path) -> None:
    lines = ["date Tue May 14 10:00:00.000 am 2024", "base hex  timestamps absolute"]
    lines += [f"   {i / 10:.6f} 1  F01x   Rx   d 8 {DATA}" for i in range(30)]
    path = tmp_path / "export.log"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with open_input(str(path)) as reader:
        list(reader)
    assert len(reader.notes) == 1 and "--format asc" in reader.notes[0]


def test_a_ten_byte_frame_is_refused_in_both_layouts() -> None:
    from analyzer.inputs.candump.reader import CandumpParser

    ten = "00 11 22 33 44 55 66 77 88 99"
    lines = [
        b"(1.0) can0 123#00112233445566778899",
        b"(1.0) can0 123##000112233445566778899",
        f"  can0  123   [10]  {ten}".encode(),
        f"(1.0) can0 123 [10] {ten}".encode(),
    ]
    items = CandumpParser("x.log").parse_lines(lines)
    assert [i.fields["line"] for i in items] == [1, 2, 3, 4]  # type: ignore[union-attr]
    ok = CandumpParser("x.log").parse_lines(
        [b"(1.0) can0 123##0" + b"00" * 12, b"  can0  123   [12]  " + b"00 " * 12]
    )
    assert [len(f.data) for f in ok] == [12, 12]  # type: ignore[union-attr]
