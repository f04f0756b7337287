"""ArduPilot DataFlash logs: CANF / CAFD by column names, GPS time to UTC, damage and resync.

The logs are written as AP_Logger writes them (tests/log_makers.py) and hold the 629
frames of samples/flight-candump.log; pymavlink's DFReader, ArduPilot's own reader,
is the reference for what the records say.
"""

from __future__ import annotations

import calendar
import gzip
import os
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pymavlink import DFReader

from analyzer.inputs import InputReader, detect_format, open_input
from analyzer.inputs.dataflash.gps_time import gps_to_utc, leap_seconds, utc_to_gps
from analyzer.protocol.types import BAD_FRAME, CanFrame, Event
from tests.log_makers import (
    CAFD,
    CANF,
    EFF,
    DataFlashWriter,
    ardupilot_log,
    flight_frames,
    lua_log,
    start_log,
)

FRAMES = flight_frames()
T0 = 1_715_680_800.0  # 2024-05-14 10:00:00 UTC, the sample's first second
BOOT = T0 - 95.0  # the autopilot booted 95 s before the sample starts
ROOT = Path(__file__).resolve().parent.parent


def read(path: Path, fmt: str | None = None) -> tuple[list[CanFrame], list[Event], InputReader]:
    reader = open_input(str(path), fmt)
    with reader:
        items = list(reader)
    frames = [i for i in items if isinstance(i, CanFrame)]
    events = [i for i in items if isinstance(i, Event)]
    assert len(frames) + len(events) == len(items)
    return frames, events, reader


def same_frames(got: list[CanFrame], want: list[CanFrame], offset: float = 0.0) -> None:
    assert len(got) == len(want)
    for a, b in zip(got, want, strict=True):
        assert (a.can_id, a.data, a.extended, a.is_remote) == (
            b.can_id,
            b.data,
            b.extended,
            b.is_remote,
        )
        assert a.time == pytest.approx(b.time - offset, abs=1e-6)


@pytest.fixture(scope="module")
def ardupilot(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[int]]:
    log, offsets = ardupilot_log(FRAMES, BOOT)
    path = tmp_path_factory.mktemp("df") / "00000042.BIN"
    path.write_bytes(log)
    return path, offsets


def test_the_sample_has_629_frames() -> None:
    assert len(FRAMES) == 629


def test_canf_records_give_the_frames_on_utc_from_gps_time(
    ardupilot: tuple[Path, list[int]],
) -> None:
    path, _ = ardupilot
    assert detect_format(str(path)) == "dataflash"
    frames, events, reader = read(path)
    assert events == []
    same_frames(frames, FRAMES)
    assert {f.channel for f in frames} == {"bus0"}
    assert "GPS" in (reader.time_base or "")
    assert reader.first_time == pytest.approx(T0 + 0.01, abs=1e-6)
    assert reader.stats["can_records"] == 629


def test_dfreader_reads_the_same_records(ardupilot: tuple[Path, list[int]]) -> None:
    path, _ = ardupilot
    frames, _, _ = read(path)
    log = DFReader.DFReader_binary(str(path))
    records = []
    while (m := log.recv_match(type="CANF")) is not None:
        records.append(m)
    assert len(records) == len(frames)
    for frame, m in zip(frames, records, strict=True):
        assert frame.can_id == m.Id & 0x1FFFFFFF
        assert frame.extended == bool(m.Id & EFF)
        assert frame.channel == f"bus{m.Bus}"
        assert frame.data == bytes(getattr(m, f"B{i}") for i in range(m.DLC))
        assert frame.time == pytest.approx(m._timestamp, abs=1e-6)  # both take 18 leap s in 2024


def test_a_lua_script_canf_without_gps_keeps_times_since_boot(tmp_path: Path) -> None:
    path = tmp_path / "lua.bin"  # a lower-case .bin: told from a raw dump by its content
    path.write_bytes(lua_log(FRAMES, BOOT))
    assert detect_format(str(path)) == "dataflash"
    frames, events, reader = read(path)
    assert events == []
    same_frames(frames, FRAMES, offset=BOOT)
    assert {f.channel for f in frames} == {"scripting"}
    assert "since the autopilot booted" in (reader.time_base or "")
    assert any("since the autopilot booted" in n for n in reader.notes)


def test_a_log_without_extension_is_recognised_by_its_fmt_header(
    ardupilot: tuple[Path, list[int]], tmp_path: Path
) -> None:
    path = tmp_path / "flight"
    path.write_bytes(ardupilot[0].read_bytes())
    assert detect_format(str(path)) == "dataflash"


def test_a_record_cut_short_is_reported_and_the_next_ones_read(
    ardupilot: tuple[Path, list[int]], tmp_path: Path
) -> None:
    source, offsets = ardupilot
    log = bytearray(source.read_bytes())
    at = offsets[100]
    del log[at + 10 : at + 16]  # six bytes of frame 100 lost (a bad SD card sector)
    path = tmp_path / "cut.BIN"
    path.write_bytes(bytes(log))
    frames, events, reader = read(path)
    same_frames(frames, FRAMES[:100] + FRAMES[101:])
    assert len(events) == 1 and events[0].fields["kind"] == BAD_FRAME
    assert f"byte {at:,}" in events[0].fields["detail"]
    assert "cut short" in events[0].fields["detail"]
    assert reader.stats["damaged_spots"] == 1


def test_garbage_between_records_is_skipped_to_the_next_a3_95(
    ardupilot: tuple[Path, list[int]], tmp_path: Path
) -> None:
    source, offsets = ardupilot
    log = bytearray(source.read_bytes())
    at = offsets[300]
    log[at:at] = b"\xa3\x95\xff" + bytes(range(40))  # a header of no known type, then noise
    path = tmp_path / "noise.BIN"
    path.write_bytes(bytes(log))
    frames, events, _ = read(path)
    same_frames(frames, FRAMES)
    assert len(events) == 1
    assert "43 byte(s) skipped" in events[0].fields["detail"]
    assert events[0].fields["offset"] == at


def test_a_log_cut_off_inside_a_record_keeps_every_whole_frame(
    ardupilot: tuple[Path, list[int]], tmp_path: Path
) -> None:
    source, offsets = ardupilot
    path = tmp_path / "cut-off.BIN"
    path.write_bytes(source.read_bytes()[: offsets[-1] + 9])
    frames, events, _ = read(path)
    same_frames(frames, FRAMES[:-1])
    assert len(events) == 1 and "ends inside a record" in events[0].fields["detail"]


def test_padding_after_the_last_record_is_only_a_note(
    ardupilot: tuple[Path, list[int]], tmp_path: Path
) -> None:
    path = tmp_path / "padded.BIN"
    path.write_bytes(ardupilot[0].read_bytes() + b"\xff" * 200)
    frames, events, reader = read(path)
    assert len(frames) == 629 and events == []
    assert any("padding" in n for n in reader.notes)


def test_cafd_records_give_can_fd_frames(tmp_path: Path) -> None:
    writer = DataFlashWriter()
    start_log(writer, [CANF, CAFD])
    payload = bytes(range(1, 13))
    d_words = [
        int.from_bytes(payload.ljust(64, b"\0")[i : i + 8], "little") for i in range(0, 64, 8)
    ]
    writer.record(CAFD, 2_000_000, 1, 0xF01 | EFF, 9, *d_words)  # DLC 9: 12 bytes
    writer.record(CAFD, 2_000_100, 1, 0x123, 8, *[0x0807060504030201] + [0] * 7)
    path = tmp_path / "fd.bin"
    path.write_bytes(bytes(writer.out))
    frames, events, _ = read(path)
    assert events == []
    assert [(f.can_id, f.data, f.is_fd, f.channel, f.extended) for f in frames] == [
        (0xF01, payload, True, "bus1", True),
        (0x123, bytes(range(1, 9)), True, "bus1", False),
    ]


def test_gps_time_to_utc_counts_leap_seconds() -> None:
    assert leap_seconds(0) == 0  # 1980
    new_year_2017 = calendar.timegm((2017, 1, 1, 0, 0, 0))
    assert gps_to_utc(*utc_to_gps(new_year_2017 - 1)) == new_year_2017 - 1
    assert gps_to_utc(*utc_to_gps(new_year_2017 + 1)) == new_year_2017 + 1
    week, ms = utc_to_gps(new_year_2017 + 1)
    assert week * 604_800 + ms / 1000 + 315_964_800 - (new_year_2017 + 1) == 18
    week, ms = utc_to_gps(new_year_2017 - 1)
    assert week * 604_800 + ms / 1000 + 315_964_800 - (new_year_2017 - 1) == 17
    assert utc_to_gps(T0) == (2314, 208_818_000)  # 2024-05-14 10:00:18 GPS, a Tuesday


def test_decode_command_reads_the_log_as_the_candump_sample(
    ardupilot: tuple[Path, list[int]],
) -> None:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}

    def summary(path: str, *extra: str) -> str:
        done = subprocess.run(
            [sys.executable, "-m", "analyzer", "decode", "--summary", path, *extra],
            capture_output=True, text=True, env=env, cwd=ROOT, timeout=60, check=True, encoding="utf-8",
        )  # fmt: skip
        return done.stdout + done.stderr

    ours = summary(str(ardupilot[0]))
    sample = summary("samples/flight-candump.log")
    assert "CRC errors     1 of 39" in ours and "CRC errors     1 of 39" in sample
    for line in ("/gimbal/command              45", "/uav/gps                    100"):
        assert line in ours and line in sample
    forced = summary(str(ardupilot[0]), "--format", "stream")
    assert "looks like an ArduPilot DataFlash log, not a raw TCP/UART stream" in forced
    assert "read it with --format dataflash" in forced
    assert "40 of 40 framed messages failed their CRC): it is an ArduPilot DataFlash log" in forced


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(data=st.data())
def test_damaged_logs_never_raise_and_give_only_real_frames(
    data: st.DataObject, tmp_path: Path
) -> None:
    log = bytearray(ardupilot_log(FRAMES[:40], BOOT)[0])
    for _ in range(data.draw(st.integers(1, 4))):
        at = data.draw(st.integers(0, len(log) - 1))
        action = data.draw(st.sampled_from(["flip", "cut", "insert"]))
        if action == "flip":
            log[at] ^= data.draw(st.integers(1, 255))
        elif action == "cut":
            del log[at : at + data.draw(st.integers(1, 40))]
        else:
            log[at:at] = data.draw(st.binary(min_size=1, max_size=40))
    path = tmp_path / "fuzz.BIN"
    path.write_bytes(bytes(log))
    frames, events, _ = read(path, "dataflash")
    assert all(e.fields["kind"] == BAD_FRAME for e in events)
    assert len(frames) <= 40 + len(events)


def test_a_gzipped_log_is_read_and_a_cut_in_it_reported(
    ardupilot: tuple[Path, list[int]], tmp_path: Path
) -> None:
    packed = gzip.compress(ardupilot[0].read_bytes())
    whole = tmp_path / "00000042.BIN.gz"
    whole.write_bytes(packed)
    frames, events, _ = read(whole)
    assert events == []
    same_frames(frames, FRAMES)
    cut = tmp_path / "cut.BIN.gz"
    cut.write_bytes(packed[: len(packed) * 3 // 4])
    frames, events, _ = read(cut)
    assert 0 < len(frames) < 629
    same_frames(frames, FRAMES[: len(frames)])
    assert any("gzip file is cut off" in e.fields["detail"] for e in events)


@settings(
    max_examples=80, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    tail=st.lists(
        st.sampled_from([b"\xa3\x95", b"\xa3\x95\xc8", b"\xa3\x95\x80", b"\x00", b"\xff"])
        | st.binary(max_size=30),
        max_size=40,
    )
)
def test_any_bytes_after_the_formats_never_raise(tmp_path: Path, tail: list[bytes]) -> None:
    writer = DataFlashWriter()
    start_log(writer, [CANF, CAFD])
    path = tmp_path / "fuzz.bin"
    path.write_bytes(bytes(writer.out) + b"".join(tail))
    frames, events, reader = read(path, "dataflash")
    assert all(e.fields["kind"] == BAD_FRAME for e in events)
    assert all(len(f.data) <= 64 for f in frames)
    assert reader.position_bytes == path.stat().st_size


def test_canf_columns_are_taken_by_name_whatever_their_order(tmp_path: Path) -> None:
    writer = DataFlashWriter()
    start_log(writer, [])
    # A build that puts DLC and Id before Bus, under another message id.
    writer.fmt(77, "CANF", "QBIBBBBBBBBB", "TimeUS,DLC,Id,Bus,B0,B1,B2,B3,B4,B5,B6,B7")
    for frame in FRAMES[:30]:
        ident = frame.can_id | (EFF if frame.extended else 0)
        us = round((frame.time - BOOT) * 1e6)
        writer.record(77, us, len(frame.data), ident, 2, *frame.data.ljust(8, b"\0"))
    # A CANF this reader cannot take: no DLC column.
    writer.fmt(78, "CAFD", "QBI", "TimeUS,Bus,Id")
    writer.record(78, 5, 0, 0x123)
    path = tmp_path / "reordered.bin"
    path.write_bytes(bytes(writer.out))
    frames, events, reader = read(path)
    assert events == []
    same_frames(frames, FRAMES[:30], offset=BOOT)
    assert {f.channel for f in frames} == {"bus2"}
    assert (
        "1 CAFD record(s) (type 78) could not be read as CAN frames: it has no DLC column"
        in reader.notes
    )
