"""ASC, TRC and CSV logs with damaged lines, relative ASC times, truncated BLF: all read through."""

from __future__ import annotations

import datetime
import gzip
import itertools
import random
from pathlib import Path
from typing import Any

import can
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from analyzer.inputs import open_input
from analyzer.protocol.codec import encode_command
from analyzer.protocol.types import BAD_FRAME, BAD_LINE, CanFrame, Event
from tests.test_fuzz_readers import TEXT_NOISE, mangle_line

T0 = 1_715_680_800.0  # 2024-05-14 10:00:00 UTC


def flight(count: int = 30) -> list[can.Message]:
    """Commands to the gimbal (extended ID 0xF01), 100 ms apart."""
    return [
        can.Message(
            timestamp=T0 + i * 0.1,
            arbitration_id=0xF01,
            data=encode_command("look_down") if i % 2 else encode_command("forward"),
            channel=0,
        )
        for i in range(count)
    ]


def write(path: Path, msgs: list[can.Message]) -> Path:
    """The file as python-can's own writer (ASCWriter, TRCWriter, CSVWriter) makes it."""
    with can.Logger(str(path)) as logger:
        for msg in msgs:
            logger.on_message_received(msg)
    return path


def items_of(path: Path) -> tuple[list[CanFrame], list[Event], Any]:
    frames: list[CanFrame] = []
    events: list[Event] = []
    reader = open_input(str(path))
    with reader:
        for item in reader:
            if isinstance(item, CanFrame):
                frames.append(item)
            else:
                assert isinstance(item, Event)
                events.append(item)
    return frames, events, reader


def first_frame_line(lines: list[str], fmt: str) -> int:
    """Index of the first frame line in a written file."""
    for i, line in enumerate(lines):
        if fmt == "csv" and i > 0:
            return i
        if fmt == "trc" and line.strip() and not line.startswith(";"):
            return i
        if fmt == "asc" and " Rx " in line:
            return i
    raise AssertionError("no frame line")


DAMAGE = {
    # A byte that is no hex digit, as a bad USB-serial adapter or a disk error leaves it.
    "asc": lambda line: line.replace(" d 8 ", " d 8 Z", 1),
    "trc": lambda line: line.replace(" Rx ", " Rx ", 1).rsplit(" ", 1)[0] + " G7\n",
    "csv": lambda line: line.replace(",0x", ",0xQ", 1),
}


def test_each_text_format_reads_every_valid_frame_after_a_damaged_line(tmp_path: Path) -> None:
    for fmt, damage in DAMAGE.items():
        path = write(tmp_path / f"flight.{fmt}", flight(30))
        lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
        first = first_frame_line(lines, fmt)
        bad = first + 7  # the 8th frame
        lines[bad] = damage(lines[bad])
        path.write_text("".join(lines), encoding="utf-8")
        frames, events, reader = items_of(path)
        expected = [m for i, m in enumerate(flight(30)) if i != 7]
        assert len(frames) == 29, fmt
        assert [round(f.time, 3) for f in frames] == [round(m.timestamp, 3) for m in expected]
        assert [f.data for f in frames] == [bytes(m.data) for m in expected], fmt
        assert len(events) == 1, (fmt, events)
        assert events[0].fields["kind"] == BAD_LINE
        assert events[0].fields["line"] == bad + 1, fmt
        assert f"line {bad + 1}:" in events[0].fields["detail"]
        assert reader.stats["bad_lines"] == 1
        assert reader.stats["frames"] == 29


def test_damaged_lines_in_a_gzipped_asc(tmp_path: Path) -> None:
    plain = write(tmp_path / "f.asc", flight(30))
    lines = plain.read_text(encoding="utf-8").splitlines(keepends=True)
    first = first_frame_line(lines, "asc")
    for k in (3, 4, 20):
        lines[first + k] = DAMAGE["asc"](lines[first + k])
    packed = tmp_path / "f.asc.gz"
    packed.write_bytes(gzip.compress("".join(lines).encode()))
    frames, events, _ = items_of(packed)
    assert len(frames) == 27
    assert [e.fields["line"] for e in events] == [first + 4, first + 5, first + 21]


def vector_relative_asc(deltas: list[float]) -> str:
    """An ASC export of CANalyzer with 'timestamps relative': each time is since the
    previous frame; the layout is that of Vector's logging block (see python-can's
    test/data/logfile.asc for the absolute variant)."""
    out = [
        "date Tue May 14 10:00:00.000 am 2024",
        "base hex  timestamps relative",
        "internal events logged",
        "// version 9.0.0",
        "Begin Triggerblock Tue May 14 10:00:00.000 am 2024",
        "   0.000000 Start of measurement",
    ]
    data = " ".join(f"{b:02X}" for b in encode_command("forward"))
    for delta in deltas:
        out.append(f"   {delta:.6f} 1  F01x            Rx   d 8 {data}")
    out.append("End TriggerBlock")
    return "\n".join(out) + "\n"


def test_relative_asc_times_are_added_up_from_the_header_date(tmp_path: Path) -> None:
    path = tmp_path / "relative.asc"
    path.write_text(vector_relative_asc([0.0] + [0.1] * 20), encoding="utf-8")  # 2 s of frames
    frames, events, reader = items_of(path)
    start = datetime.datetime(2024, 5, 14, 10, 0, 0).timestamp()  # local time, as Vector
    assert events == []
    assert len(frames) == 21
    assert frames[0].time == start
    assert abs(frames[-1].time - frames[0].time - 2.0) < 1e-6
    assert all(b.time > a.time for a, b in itertools.pairwise(frames))
    assert reader.time_base is not None and "previous frame" in reader.time_base


def test_relative_asc_keeps_counting_time_over_a_damaged_line(tmp_path: Path) -> None:
    path = tmp_path / "relative.asc"
    text = vector_relative_asc([0.5] * 10).splitlines(keepends=True)
    text[10] = DAMAGE["asc"](text[10])
    path.write_text("".join(text), encoding="utf-8")
    frames, events, _ = items_of(path)
    assert len(frames) == 9 and len(events) == 1
    assert abs(frames[-1].time - frames[0].time - 4.5) < 1e-6


def test_absolute_asc_keeps_its_times(tmp_path: Path) -> None:
    path = write(tmp_path / "abs.asc", flight(5))
    frames, _, reader = items_of(path)
    assert [round(f.time, 3) for f in frames] == [round(T0 + i * 0.1, 3) for i in range(5)]
    assert reader.time_base == "absolute"


# -- BLF -------------------------------------------------------------------------------------


def test_truncated_blf_keeps_everything_before_the_cut(tmp_path: Path) -> None:
    # A logger that loses power leaves the file cut inside its last object; the file
    # header is never finalised either. python-can's BLFWriter compresses objects into
    # containers of about 128 KiB, so a long flight makes several.
    msgs = [
        can.Message(timestamp=T0 + i * 0.001, arbitration_id=0xF01, data=bytes([i % 256] * 8))
        for i in range(20_000)
    ]
    full = tmp_path / "full.blf"
    with can.BLFWriter(str(full)) as writer:
        for msg in msgs:
            writer.on_message_received(msg)
    whole = full.read_bytes()
    cut = tmp_path / "cut.blf"
    cut.write_bytes(whole[: len(whole) * 3 // 4])
    frames, events, _ = items_of(cut)
    assert 0 < len(frames) < 20_000
    assert [f.data for f in frames] == [bytes(m.data) for m in msgs[: len(frames)]]
    assert len(events) == 1 and events[0].fields["kind"] == BAD_FRAME
    assert "cut off" in events[0].fields["detail"]
    assert f"{len(frames):,} frames" in events[0].fields["detail"]
    complete, none, _ = items_of(full)
    assert len(complete) == 20_000 and none == []


# -- properties ------------------------------------------------------------------------------


@pytest.mark.slow
@settings(max_examples=30, deadline=None)
@given(
    fmt=st.sampled_from(sorted(DAMAGE)),
    where=st.integers(0, 11),
    junk=st.text(alphabet=st.characters(codec="utf-8"), max_size=80),
)
def test_any_damaged_line_costs_at_most_that_line(
    tmp_path_factory: Any, fmt: str, where: int, junk: str
) -> None:
    path = write(tmp_path_factory.mktemp("d") / f"f.{fmt}", flight(12))
    lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
    first = first_frame_line(lines, fmt)
    lines[first + where] = junk.replace("\n", " ").replace("\r", " ") + "\n"
    path.write_text("".join(lines), encoding="utf-8")
    frames, events, _ = items_of(path)
    kept = [bytes(m.data) for i, m in enumerate(flight(12)) if i != where]
    got = [f.data for f in frames]
    assert len(got) in (11, 12)
    it = iter(got)
    assert all(any(data == g for g in it) for data in kept)  # in order, none lost
    assert all(e.fields["kind"] == BAD_LINE for e in events)
    assert len(events) <= 1


# -- lines python-can would skip without a word ----------------------------------------------


def test_an_asc_frame_whose_time_is_damaged_is_a_bad_line_not_a_silent_loss(
    tmp_path: Path,
) -> None:
    # python-can's ASCReader skips a line whose time column is no decimal number (1e309,
    # nan, garbage) as if it were a comment; the frame must not vanish without a word.
    written = (
        write(tmp_path / "clean.asc", flight(12))
        .read_text(encoding="utf-8")
        .splitlines(keepends=True)
    )
    first = first_frame_line(written, "asc")
    for noise in TEXT_NOISE:
        lines = list(written)
        time_word = lines[first + 5].split()[0]
        lines[first + 5] = lines[first + 5].replace(time_word, noise, 1)
        path = tmp_path / "damaged.asc"
        path.write_text("".join(lines), encoding="utf-8")
        frames, events, reader = items_of(path)
        assert len(frames) == 11, noise
        assert [e.fields["line"] for e in events] == [first + 6], noise
        assert events[0].fields["kind"] == BAD_LINE
        assert "not a ASC frame" in events[0].fields["detail"]
        assert reader.stats["bad_lines"] == 1


def test_a_relative_asc_time_of_1e309_adds_no_time(tmp_path: Path) -> None:
    path = tmp_path / "relative.asc"
    text = vector_relative_asc([0.5] * 10).splitlines(keepends=True)
    text[10] = text[10].replace("0.500000", "1e309", 1)
    path.write_text("".join(text), encoding="utf-8")
    frames, events, _ = items_of(path)
    assert len(frames) == 9 and [e.fields["line"] for e in events] == [11]
    assert abs(frames[-1].time - frames[0].time - 4.0) < 1e-6


def test_a_trc_frame_whose_type_column_is_damaged_is_a_bad_line(tmp_path: Path) -> None:
    # python-can's TRCReader drops a record of an unknown type at log level INFO.
    lines = (
        write(tmp_path / "clean.trc", flight(12))
        .read_text(encoding="utf-8")
        .splitlines(keepends=True)
    )
    first = first_frame_line(lines, "trc")
    lines[first + 3] = lines[first + 3].replace(" DT ", " nan ", 1)
    path = tmp_path / "damaged.trc"
    path.write_text("".join(lines), encoding="utf-8")
    frames, events, _ = items_of(path)
    assert len(frames) == 11
    assert [e.fields["line"] for e in events] == [first + 4]
    assert "'nan'" in events[0].fields["detail"]
    # A ';' where the message number was makes python-can take a frame for a comment,
    # the first one (then read as the header's last line) included.
    for k in (0, 6):
        lines[first + k] = lines[first + k].replace(f"{k} ", "; ", 1)
    path.write_text("".join(lines), encoding="utf-8")
    frames, events, _ = items_of(path)
    assert len(frames) == 9
    assert [e.fields["line"] for e in events] == [first + 1, first + 4, first + 7]


def test_asc_and_trc_events_that_are_no_frames_are_not_damage(tmp_path: Path) -> None:
    asc = vector_relative_asc([0.1] * 3).splitlines(keepends=True)
    asc[7:7] = [
        "   0.100000 1  Statistic: D 0 R 3 XD 0 XR 0 E 0 O 0 B 0.10%\n",
        "   0.100000 CAN 1 Status:chip status error active\n",
        "   0.100000 SV: 1 0 1 ::System::Voltage = 12.1\n",
        "   0.100000 1  J1939TP FEE3p        6    0  0   -   Rx   d 23 A0 0F A6 60 3B D1\n",
        "// a comment\n",
        "\n",
    ]
    (tmp_path / "events.asc").write_text("".join(asc), encoding="utf-8")
    frames, events, _ = items_of(tmp_path / "events.asc")
    assert len(frames) == 3 and events == []
    trc = (
        write(tmp_path / "plain.trc", flight(3))
        .read_text(encoding="utf-8")
        .splitlines(keepends=True)
    )
    first = first_frame_line(trc, "trc")
    trc.insert(first + 1, "      9       100.000 ST  1  Bus heavy\n")
    (tmp_path / "events.trc").write_text("".join(trc), encoding="utf-8")
    frames, events, _ = items_of(tmp_path / "events.trc")
    assert len(frames) == 3 and events == []


@settings(max_examples=60, deadline=None)
@given(fmt=st.sampled_from(["asc", "trc", "csv"]), seed=st.integers(0, 2**32))
def test_a_mangled_frame_line_is_read_or_reported_never_dropped(
    tmp_path_factory: Any, fmt: str, seed: int
) -> None:
    # The fuzz test's own damage of a text line, on the frame lines of python-can's file.
    path = write(tmp_path_factory.mktemp("m") / f"f.{fmt}", flight(12))
    lines = path.read_bytes().split(b"\n")
    first = first_frame_line([line.decode() for line in lines], fmt)
    head, body = lines[:first], lines[first : first + 12]
    mangled, how = mangle_line(random.Random(seed), b"\n".join(body), b"")
    index = int(how.split(":")[0].split()[1]) - 1
    path.write_bytes(b"\n".join([*head, mangled, *lines[first + 12 :]]))
    frames, events, _ = items_of(path)
    reported = [e for e in events if "line" in e.fields]
    assert all(e.fields["kind"] == BAD_LINE for e in events)
    blank = not mangled.split(b"\n")[index].strip()  # no line left to speak of
    assert len(frames) + len(reported) >= 12 - blank, (how, events)
