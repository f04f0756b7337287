"""CSV logs: SavvyCAN's native CSV told apart by its header, python-can CSV with damaged lines.

Both hold the 629 frames of samples/flight-candump.log: the SavvyCAN file as
FrameFileIO::saveNativeCSVFile writes it, the python-can file by can.Logger itself.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from analyzer.inputs import InputReader, detect_format, open_input
from analyzer.inputs.base import ABSOLUTE, RELATIVE_TO_START
from analyzer.protocol.types import BAD_LINE, CanFrame, Event
from tests.log_makers import flight_frames, python_can_log, savvycan_csv

FRAMES = flight_frames()


def read(path: Path, fmt: str | None = None) -> tuple[list[CanFrame], list[Event], InputReader]:
    reader = open_input(str(path), fmt)
    with reader:
        items = list(reader)
    frames = [i for i in items if isinstance(i, CanFrame)]
    return frames, [i for i in items if isinstance(i, Event)], reader


def same(got: list[CanFrame], want: list[CanFrame], offset: float = 0.0) -> None:
    assert [(f.can_id, f.data, f.extended) for f in got] == [
        (f.can_id, f.data, f.extended) for f in want
    ]
    assert all(
        a.time == pytest.approx(b.time - offset, abs=1e-6) for a, b in zip(got, want, strict=True)
    )


def test_savvycan_csv_is_recognised_by_its_header_and_gives_the_frames(tmp_path: Path) -> None:
    path = tmp_path / "savvy.csv"
    path.write_text(savvycan_csv(FRAMES), encoding="utf-8")
    assert detect_format(str(path)) == "savvycan"
    frames, events, reader = read(path)
    assert events == []
    same(frames, FRAMES)
    assert {(f.channel, f.direction) for f in frames} == {("bus0", "rx")}
    assert reader.time_base == ABSOLUTE
    assert reader.stats == {"lines": 630, "frames": 629, "bad_lines": 0}


def test_savvycan_times_since_the_capture_started_are_relative(tmp_path: Path) -> None:
    start = FRAMES[0].time
    shifted = [CanFrame(f.time - start, f.can_id, f.data, f.extended) for f in FRAMES[:20]]
    path = tmp_path / "relative.csv"
    path.write_text(savvycan_csv(shifted), encoding="utf-8")
    frames, _, reader = read(path)
    same(frames, FRAMES[:20], offset=start)
    assert reader.time_base == RELATIVE_TO_START


def test_a_damaged_savvycan_line_is_reported_and_the_next_is_read(tmp_path: Path) -> None:
    lines = savvycan_csv(FRAMES).splitlines(keepends=True)
    lines[5] = lines[5].replace(",true,", ",maybe,", 1)
    lines[6] = lines[6][:20] + "\n"  # cut short
    path = tmp_path / "damaged.csv"
    path.write_text("".join(lines), encoding="utf-8")
    frames, events, _ = read(path)
    same(frames, FRAMES[:4] + FRAMES[6:])
    assert [e.fields["line"] for e in events] == [6, 7]
    assert all(e.fields["kind"] == BAD_LINE for e in events)


def python_can_csv(path: Path, frames: list[CanFrame]) -> list[str]:
    return python_can_log(path, frames).read_text(encoding="utf-8").splitlines(keepends=True)


@pytest.mark.parametrize("header", [True, False])
def test_python_can_csv_with_three_bad_lines_keeps_every_other_frame(
    tmp_path: Path, header: bool
) -> None:
    path = tmp_path / "flight.csv"
    lines = python_can_csv(path, FRAMES)
    bad = [10, 11, 300]  # two in a row: each restart must read the very next line
    dropped = {k - 1 for k in bad}  # the frames of those lines (line 1 is the header)
    for k in bad:
        lines[k] = lines[k].replace(",", ";", 1)
    if not header:  # a file cut out of a longer log, without its header line
        lines = lines[1:]
        bad = [k - 1 for k in bad]
    path.write_text("".join(lines), encoding="utf-8")
    frames, events, reader = read(path, "csv")
    same(frames, [f for i, f in enumerate(FRAMES) if i not in dropped])
    assert [e.fields["line"] for e in events] == [k + 1 for k in bad]
    assert reader.stats["bad_lines"] == 3


def test_a_savvycan_file_read_as_python_can_csv_reports_every_line(tmp_path: Path) -> None:
    path = tmp_path / "savvy.csv"
    path.write_text(savvycan_csv(FRAMES[:30]), encoding="utf-8")
    frames, events, _ = read(path, "csv")
    assert frames == []
    assert [e.fields["line"] for e in events if "line" in e.fields] == list(range(1, 32))


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    lines=st.lists(st.text(alphabet="0123456789ABCDEFabcdeftruxRT,. -", max_size=60), max_size=12)
)
def test_any_savvycan_lines_never_raise(tmp_path: Path, lines: list[str]) -> None:
    path = tmp_path / "fuzz.csv"
    path.write_text(
        "Time Stamp,ID,Extended,Dir,Bus,LEN,D1,D2,D3,D4,D5,D6,D7,D8\n" + "\n".join(lines),
        encoding="utf-8",
    )
    frames, events, _ = read(path)
    assert len(frames) + len(events) <= len(lines)
