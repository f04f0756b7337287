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
from analyzer.inputs.candump import DECIDE_AFTER
from analyzer.inputs.python_can_text import ABSOLUTE, DELTA, RELATIVE_TO_START
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
    path.write_text(text)
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
    path.write_text(screen(["000.000000"] + ["000.100000", "000.050000"] * 10))
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
