"""Damage before a capture's first frame takes that frame's time, never 0 (1970): a log cut
at its start, a header line, a timestamp damaged into another number. A recording of the
file never starts before the capture.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from analyzer.capture_clock import MAX_BACK_S, CaptureClock
from analyzer.protocol.types import BAD_LINE, CanFrame, Event, diagnostic
from tests.fleet_flights import cli_output as cli
from tests.log_makers import flight_frames, python_can_log, savvycan_csv
from tests.test_frame_columns import as_columns

FRAMES = flight_frames()[:60]
FIRST = FRAMES[0].time


def candump(frames: list[CanFrame]) -> str:
    return "".join(f"({f.time:.6f}) can0 {f.can_id:08X}#{f.data.hex().upper()}\n" for f in frames)


def written(fmt: str, folder: Path) -> Path:
    """The frames in ``fmt`` as the real tool writes it."""
    if fmt == "candump":
        path = folder / "flight.log"
        path.write_text(candump(FRAMES), encoding="utf-8")
    elif fmt == "savvycan":
        path = folder / "flight.csv"
        path.write_text(savvycan_csv(FRAMES), encoding="utf-8")
    else:
        path = python_can_log(folder / f"flight.{fmt}", FRAMES)
    return path


def first_frame_line(lines: list[str], fmt: str) -> int:
    """The index of the line of the first frame."""
    if fmt == "candump":
        return 0
    if fmt in ("savvycan", "csv"):
        return 1
    if fmt == "trc":
        return next(i for i, line in enumerate(lines) if not line.startswith(";"))
    return next(i for i, line in enumerate(lines) if "Rx" in line)


def cut_at_start(path: Path, fmt: str) -> Path:
    """The first frame's line cut in the middle, as a log copied from its middle is."""
    lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
    n = first_frame_line(lines, fmt)
    lines[n] = lines[n][len(lines[n]) // 2 :]
    path.write_text("".join(lines), encoding="utf-8")
    return path


def events(path: Path, *options: str) -> list[dict[str, object]]:
    return [json.loads(line) for line in cli("decode", str(path), "--json", *options).splitlines()]


def recording_start(path: Path, folder: Path) -> float:
    out = folder / "cut.mcap"
    cli("convert", str(path), "-o", str(out), "-q", "-f")
    info = json.loads(cli("info", str(out), "--json"))
    return float(info["start_time"])


@pytest.mark.parametrize("fmt", ["candump", "asc", "trc", "csv", "savvycan"])
def test_a_log_cut_at_its_start_is_dated_by_its_first_frame(fmt: str, tmp_path: Path) -> None:
    path = written(fmt, tmp_path)
    whole = [float(e["time"]) for e in events(path)]  # type: ignore[arg-type]
    found = events(cut_at_start(path, fmt))
    damage = [e for e in found if e["topic"] == "/diagnostics"]
    assert damage, "the cut line is reported"
    good = min(float(e["time"]) for e in found if e["topic"] != "/diagnostics")  # type: ignore[arg-type]
    assert good == whole[1]  # the second frame's, as the file dates it
    assert all(float(e["time"]) >= good for e in damage)  # type: ignore[arg-type]
    assert recording_start(path, tmp_path) == pytest.approx(good, abs=1e-3)


def test_a_header_line_before_a_candump_log(tmp_path: Path) -> None:
    path = tmp_path / "flight.log"
    path.write_text(
        "# candump -L can0, started by the logger\n" + candump(FRAMES), encoding="utf-8"
    )
    (note, first) = events(path)[:2]
    assert note["kind"] == BAD_LINE and note["time"] == first["time"] == pytest.approx(FIRST)


def test_a_damaged_timestamp_that_still_parses_is_kept_as_a_diagnostic(tmp_path: Path) -> None:
    lines = candump(FRAMES).splitlines(keepends=True)
    lines[10] = "(0000000001" + lines[10][11:]  # leading digits lost: 1970
    lines[0] = "(0715680800" + lines[0][11:]  # a flipped digit: 1992
    path = tmp_path / "flight.log"
    path.write_text("".join(lines), encoding="utf-8")
    found = events(path)
    bad = [e for e in found if e.get("kind") == "bad_frame"]
    assert [e["stated_time"] for e in bad] == [
        pytest.approx(715680800.0, abs=1),
        pytest.approx(1.0, abs=1),
    ]
    assert all(float(e["time"]) >= FRAMES[1].time for e in found)  # type: ignore[arg-type]
    assert all(e["raw"] for e in bad)  # the frame's bytes are not lost
    start = recording_start(path, tmp_path)
    assert start == pytest.approx(FRAMES[1].time, abs=1e-3)
    summary = json.loads(cli("decode", str(path), "--summary", "--json"))
    assert summary["first_time"] == pytest.approx(FRAMES[1].time, abs=1e-3)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.integers(0, 40), st.integers(0, 255)), min_size=1, max_size=6))
def test_no_damage_to_the_first_lines_dates_anything_before_the_capture(
    hits: list[tuple[int, int]],
) -> None:
    """Bytes of the first two lines overwritten at random: whatever they become, nothing
    read from the file is timed more than the clock's limit before the good frames."""
    from analyzer.inputs.candump.reader import CandumpReader
    from analyzer.pipeline import Pipeline, run_items

    text = bytearray(candump(FRAMES).encode())
    for offset, value in hits:
        text[offset] = value if value != 0x0A else 0x20
    seen: list[float] = []

    class Times:
        def handle(self, batch: object) -> None:
            seen.extend(e.time for e in batch.events)  # type: ignore[attr-defined]

        def close(self) -> None:
            pass

    import tempfile

    with tempfile.NamedTemporaryFile(suffix=".log") as handle:
        handle.write(bytes(text))
        handle.flush()
        reader = CandumpReader(handle.name)
        run_items(reader, Pipeline([Times()]))
        reader.close()
    assert seen and min(seen) >= FRAMES[2].time - MAX_BACK_S


# -- the clock itself ----------------------------------------------------------------------------


def diag(t: float) -> Event:
    return diagnostic(t, "log", BAD_LINE, "line 1: unreadable")


def frame(t: float) -> CanFrame:
    return CanFrame(t, 0xF01, b"\x0f\x04" + bytes(6), channel="can0")


def test_diagnostics_before_the_first_frame_wait_for_it() -> None:
    clock = CaptureClock()
    out = list(clock.batches([[diag(0.0)], [diag(0.0), frame(1e9), frame(1e9 + 1)]]))
    assert [[i.time for i in chunk] for chunk in out] == [[1e9, 1e9, 1e9, 1e9 + 1]]
    assert clock.redated == 2 and clock.first == 1e9


def test_a_file_of_nothing_but_damage_keeps_its_times() -> None:
    out = list(CaptureClock().batches([[diag(0.0)], [diag(0.0)]]))
    assert [[i.time for i in chunk] for chunk in out] == [[0.0, 0.0]]


def test_a_frame_a_year_before_the_capture_is_quarantined() -> None:
    clock = CaptureClock()
    (chunk,) = clock.batches([[frame(1e9), frame(1e9 - 365 * 86400), frame(1e9 + 1)]])
    assert [type(i).__name__ for i in chunk] == ["CanFrame", "Event", "CanFrame"]
    assert chunk[1].time == 1e9 and chunk[1].fields["kind"] == "bad_frame"
    assert clock.quarantined == 1


def test_a_clock_set_back_by_an_hour_is_no_damage() -> None:
    chunks = [[frame(1e9 + i) for i in range(10)], [frame(1e9 - 3600 + i) for i in range(10)]]
    out = list(CaptureClock().batches(chunks))
    assert out == chunks


def test_columns_of_frames_are_looked_into() -> None:
    run = as_columns([frame(1e9), frame(5.0), frame(1e9 + 1)])
    (chunk,) = CaptureClock().batches([[run]])
    assert [i.time for i in chunk] == [1e9, 1e9, 1e9 + 1]
    assert isinstance(chunk[1], Event)
