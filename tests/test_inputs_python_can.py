"""python-can log formats (ASC, BLF, TRC, CSV, MF4 and .gz forms) read into CanFrames."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import can
import pytest

from analyzer.errors import UsageError
from analyzer.inputs import open_input
from analyzer.protocol.codec import encode_command
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.feedback import encode_attitude, segments
from analyzer.protocol.ids import FEEDBACK_ID
from analyzer.protocol.types import (
    BAD_LINE,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
    CanFrame,
    Event,
)

T0 = 1_700_000_000.0


def messages() -> list[can.Message]:
    out = [
        can.Message(timestamp=T0, arbitration_id=0xF01, data=encode_command("look_down")),
        can.Message(
            timestamp=T0 + 0.1, arbitration_id=0x7E8, is_extended_id=False, data=b"\x01\x02"
        ),
    ]
    feedback = segments(encode_attitude(pitch_deg=-10.0, yaw_deg=100.0, motor_yaw_deg=5.0))
    for i, seg in enumerate(feedback):
        out.append(
            can.Message(timestamp=T0 + 0.2 + i * 0.001, arbitration_id=FEEDBACK_ID, data=seg)
        )
    return out


def write(path: Path, msgs: list[can.Message]) -> Path:
    with can.Logger(str(path)) as logger:
        for msg in msgs:
            logger.on_message_received(msg)
    return path


@pytest.mark.parametrize(
    "name", ["x.asc", "x.blf", "x.trc", "x.csv", "x.mf4", "x.asc.gz", "x.trc.gz"]
)
def test_formats_read_and_decode(tmp_path: Path, name: str) -> None:
    path = write(tmp_path / name, messages())
    reader = open_input(str(path))
    frames: list[Any] = list(reader)
    assert all(isinstance(f, CanFrame) for f in frames)
    assert [f.can_id for f in frames] == [m.arbitration_id for m in messages()]
    assert [f.data for f in frames] == [bytes(m.data) for m in messages()]
    assert frames[1].extended is False
    assert reader.stats["frames"] == 6
    assert reader.position_bytes == reader.size_bytes
    decoder = ProtocolDecoder()
    topics = [e.topic for f in frames for e in decoder.feed(f)]
    assert topics == [TOPIC_COMMAND, TOPIC_GIMBAL_ATTITUDE]


@pytest.mark.parametrize("name", ["x.asc", "x.blf", "x.csv", "x.mf4"])
def test_times_are_kept(tmp_path: Path, name: str) -> None:
    frames = list(open_input(str(write(tmp_path / name, messages()))))
    assert frames[1].time - frames[0].time == pytest.approx(0.1, abs=1e-3)
    assert frames[0].time == pytest.approx(T0, abs=1e-3)


def test_explicit_format_overrides_the_extension(tmp_path: Path) -> None:
    path = write(tmp_path / "x.asc", messages())
    renamed = path.rename(tmp_path / "export.txt")
    assert len(list(open_input(str(renamed), "asc"))) == 6


def test_damaged_csv_line_is_reported_and_reading_goes_on(tmp_path: Path) -> None:
    path = write(tmp_path / "x.csv", messages())
    lines = path.read_text(encoding="utf-8").splitlines()
    lines.insert(3, "this,is,not,a,frame")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    items: list[Any] = list(open_input(str(path)))
    assert [type(i) for i in items] == [CanFrame, CanFrame, Event] + [CanFrame] * 4
    assert items[2].topic == TOPIC_DIAGNOSTICS and items[2].fields["kind"] == BAD_LINE
    assert items[2].fields["line"] == 4
    assert "line 4" in items[2].fields["detail"]


def test_mf4_without_its_package_is_a_usage_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import can.io.mf4

    path = write(tmp_path / "x.mf4", messages())
    monkeypatch.setattr(can.io.mf4, "asammdf", None)  # as where asammdf is not installed
    with pytest.raises(UsageError, match="asammdf"):
        open_input(str(path))


def test_a_text_log_that_gives_no_frame_says_so(tmp_path: Path) -> None:
    path = tmp_path / "junk.asc"
    path.write_text("this is\nnot an ASC export\nat all\n", encoding="utf-8")
    items: list[Any] = list(open_input(str(path)))
    assert all(item.fields["kind"] == BAD_LINE for item in items)
    assert [item.fields.get("line") for item in items[:-1]] == [1, 2, 3]  # each line said
    assert "no CAN frame could be read" in items[-1].fields["detail"]


def test_not_a_blf_is_a_usage_error(tmp_path: Path) -> None:
    path = tmp_path / "x.blf"
    path.write_bytes(b"this is not a BLF file at all, not even close, no" * 4)
    with pytest.raises(UsageError, match=r"x\.blf"):
        open_input(str(path))


def _blf_with(tmp_path: Path, offset: int, value: int) -> Path:
    """A real BLF (python-can's writer) with the 32-bit size field at ``offset`` changed."""
    path = write(tmp_path / "x.blf", messages())
    data = bytearray(path.read_bytes())
    data[offset : offset + 4] = value.to_bytes(4, "little")
    path.write_bytes(bytes(data))
    return path


@pytest.mark.parametrize("claim", [2_700_000_000, 10])
def test_a_blf_header_claiming_another_size_is_refused_in_one_line(
    tmp_path: Path, claim: int
) -> None:
    path = _blf_with(tmp_path, 4, claim)  # the file header's own size (144 as written)
    size = path.stat().st_size
    with pytest.raises(UsageError) as caught:
        open_input(str(path))
    message = str(caught.value)
    assert "\n" not in message
    assert f"claims to be {claim:,} bytes long in a file of {size:,} bytes" in message


def test_a_blf_object_claiming_gigabytes_costs_no_memory_and_is_reported(
    tmp_path: Path,
) -> None:
    import tracemalloc

    path = _blf_with(tmp_path, 144 + 8, 2_700_000_000)  # the first object's size
    tracemalloc.start()
    try:
        items: list[Any] = list(open_input(str(path)))
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 20_000_000  # python-can alone would have asked for 2.7 GB
    frames = [i for i in items if isinstance(i, CanFrame)]
    assert len(frames) == 6
    # The container's zlib stream ends where it does: the frames in it are read, and the
    # size it claims is said to be wrong.
    detail = items[-1].fields["detail"]
    assert "the log container at byte 144 claims 2,69" in detail
    assert "more than its compressed data holds" in detail


def test_a_blf_frame_time_beyond_any_date_is_a_bad_frame_and_reading_goes_on(
    tmp_path: Path,
) -> None:
    msgs = messages()
    msgs[1].timestamp = T0 + 9e9  # 2^33 s and more: a damaged time, no date
    items: list[Any] = list(open_input(str(write(tmp_path / "x.blf", msgs))))
    frames = [i for i in items if isinstance(i, CanFrame)]
    bad = [i for i in items if isinstance(i, Event)]
    assert len(frames) == 5 and len(bad) == 1
    assert bad[0].fields["detail"].startswith("frame 2 skipped: its time 1.07")
