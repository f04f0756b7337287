"""candump readers: every -L and screen-output variant, bad lines, accounting, blocks, gzip."""

from __future__ import annotations

import gzip
from pathlib import Path
from typing import Any

import can
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from analyzer.inputs import open_input
from analyzer.inputs.candump.reader import CandumpParser, CandumpReader
from analyzer.protocol.ids import PROTOCOL_IDS
from analyzer.protocol.types import BAD_LINE, TOPIC_DIAGNOSTICS, CanFrame, Event


def parse(*lines: bytes, **kwargs: Any) -> tuple[list[Any], CandumpParser]:
    parser = CandumpParser("test.log", **kwargs)
    return parser.parse_lines(list(lines)), parser


def one(line: bytes) -> CanFrame:
    items, _ = parse(line)
    assert len(items) == 1
    assert isinstance(items[0], CanFrame), items
    return items[0]


def assert_accounted(parser: CandumpParser) -> None:
    s = parser.stats
    assert s["lines"] == s["frames"] + s["bad_lines"] + s["blank_lines"] + s["note_lines"]


# -- candump -L ------------------------------------------------------------------------------


def test_log_line_extended_frame() -> None:
    frame = one(b"(1436509052.249713) can0 030F0001#EB900C0000000000")
    assert frame == CanFrame(
        1436509052.249713, 0x030F0001, bytes.fromhex("EB900C0000000000"), True, "can0"
    )


def test_log_line_standard_id_and_short_data() -> None:
    frame = one(b"(1.000000) vcan1 123#DEAD")
    assert (frame.can_id, frame.extended, frame.data, frame.channel) == (
        0x123,
        False,
        b"\xde\xad",
        "vcan1",
    )


@pytest.mark.parametrize(("suffix", "direction"), [(b" R", "rx"), (b" T", "tx"), (b"", "")])
def test_log_line_direction_suffix(suffix: bytes, direction: str) -> None:
    assert one(b"(1.0) can0 00000F01#0F07000000000000" + suffix).direction == direction


@pytest.mark.parametrize("text", [b"123#R", b"123#R3", b"123#r", b"123#R8_9"])
def test_log_line_remote_frames(text: bytes) -> None:
    frame = one(b"(2.5) can0 " + text)
    assert frame.is_remote and frame.data == b"" and frame.can_id == 0x123


def test_log_line_error_frame() -> None:
    frame = one(b"(3.0) can0 20000080#0000000000000000")
    assert frame.is_error and frame.can_id == 0x80


def test_log_line_can_fd() -> None:
    frame = one(b"(4.0) can0 00000F01##1" + b"AB" * 12)
    assert frame.is_fd and frame.data == b"\xab" * 12 and frame.can_id == 0xF01


def test_log_line_len8_dlc_suffix() -> None:
    frame = one(b"(5.0) can0 123#1122334455667788_C")
    assert frame.data == bytes.fromhex("1122334455667788")


def test_lowercase_hex_and_empty_data() -> None:
    assert one(b"(5.0) can0 030f0001#eb90").data == b"\xeb\x90"
    assert one(b"(5.0) can0 123#").data == b""


# -- candump screen output -------------------------------------------------------------------


def test_screen_default_output() -> None:
    frame = one(b"  can0  030F0001   [8]  EB 90 0C 00 00 00 00 00")
    assert frame.can_id == 0x030F0001 and frame.data[:3] == b"\xeb\x90\x0c"
    assert frame.time == 0.0 and frame.extended and frame.channel == "can0"


def test_screen_absolute_timestamp_and_remote() -> None:
    frame = one(b" (1436509052.249713)  can0  123   [2]  remote request")
    assert frame.is_remote and frame.time == pytest.approx(1436509052.249713)


def test_screen_date_timestamp_extra_info_fd_and_ascii() -> None:
    frame = one(
        b" (2015-07-10 08:17:32.249713)  can0  TX B -  123  [12]  "
        b"11 22 33 44 55 66 77 88 99 AA BB CC   '.\"3DUfw.....'"
    )
    assert frame.is_fd and frame.direction == "tx" and len(frame.data) == 12


def test_screen_error_frame_with_explanation_lines() -> None:
    items, parser = parse(
        b"  can0  20000080   [8]  00 00 00 00 00 00 00 00   ERRORFRAME",
        b"\tbus-error",
        b"\terror-counter-tx-rx{{0}{0}}",
        b"  can0  123   [1]  01",
    )
    assert [type(i) for i in items] == [CanFrame, CanFrame]
    assert items[0].is_error
    assert parser.stats["note_lines"] == 2
    assert_accounted(parser)


# -- bad lines -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("line", "why"),
    [
        (b"# a comment", "comment"),
        (b"(1.0) can0 12G#11", "bad CAN ID"),
        (b"(x) can0 123#11", "bad timestamp"),
        (b"(1.0) can0 123#112", "odd number"),
        (b"(1.0) can0 123#1122334455667788AA", "more than 8"),
        (b"(1.0) can0 123#11 X", "unexpected text"),
        (b"(1.0) can0 123", "no '#'"),
        (b"(1.0) can0 123#R9", "DLC"),
        (b"(1.0) can0 123###00", "CAN XL"),
        (b"(nan) can0 123#11", "bad timestamp"),
        (b"  can0  123   [3]  11 22", "3 data bytes"),
        (b"garbage", "not a candump line"),
        (b"\xff\xfe\x00 binary", "not a candump line"),
    ],
)
def test_bad_lines_become_diagnostics(line: bytes, why: str) -> None:
    items, parser = parse(b"(1.0) can0 123#11", line, b"(2.0) can0 123#22")
    assert [type(i) for i in items] == [CanFrame, Event, CanFrame]
    event = items[1]
    assert event.topic == TOPIC_DIAGNOSTICS and event.fields["kind"] == BAD_LINE
    assert event.fields["line"] == 2
    assert why in event.fields["detail"]
    assert event.time == 1.0  # the time of the line before
    assert parser.stats["bad_lines"] == 1
    assert_accounted(parser)


def test_blank_lines_are_counted_not_reported() -> None:
    items, parser = parse(b"", b"   ", b"(1.0) can0 123#11")
    assert len(items) == 1 and parser.stats["blank_lines"] == 2
    assert_accounted(parser)


# -- skipping unwanted IDs -------------------------------------------------------------------


def test_wanted_ids_skip_other_frames_but_count_them() -> None:
    lines = [
        b"(1.0) can0 18FEF100#0011223344556677",
        b"(2.0) can0 00000F01#0F07000000000000",
        b"(3.0) can0 18FEF100#0011223344556677",
        b"(4.0) can0 18FEF100#00112",  # damaged, even though its ID is not wanted
        b"(5.0) can0 20000080#0000000000000000",  # error frames always come through
        b"(6.0) can0 7E8#01",
    ]
    items, parser = parse(*lines, wanted_ids=PROTOCOL_IDS)
    kinds = [(type(i).__name__, getattr(i, "time", None)) for i in items]
    assert kinds == [("CanFrame", 2.0), ("Event", 3.0), ("CanFrame", 5.0)]
    assert parser.stats["frames"] == 5 and parser.stats["other_frames"] == 3
    assert (parser.first_time, parser.last_time) == (1.0, 6.0)
    assert_accounted(parser)


@pytest.mark.parametrize("line", [b"1(2.0) can0 123#11", b"(2.0)1 can0 123#11"])
def test_skipped_id_with_text_around_its_timestamp_is_a_bad_line(line: bytes) -> None:
    items, parser = parse(b"(1.0) can0 123#11", line, wanted_ids=PROTOCOL_IDS)
    assert [(type(i), i.fields["line"]) for i in items] == [(Event, 2)]
    assert (parser.first_time, parser.last_time) == (1.0, 1.0)
    assert_accounted(parser)


def test_skipped_and_decoded_paths_agree() -> None:
    lines = [f"({i}.5) can0 {cid}#0011".encode() for i, cid in enumerate(["123", "F01", "1FF"])]
    everything, _ = parse(*lines)
    wanted, _ = parse(*lines, wanted_ids={0xF01})
    assert wanted == [f for f in everything if f.can_id == 0xF01]


# -- files -----------------------------------------------------------------------------------


def write_log(path: Path, lines: list[str], newline: str = "\n") -> Path:
    path.write_bytes(newline.join(lines).encode() + newline.encode())
    return path


def test_reader_across_small_blocks_keeps_line_numbers(tmp_path: Path) -> None:
    lines = [f"({i}.000000) can0 00000F01#0F07000000000000" for i in range(50)]
    lines[33] = "this line is broken"
    path = write_log(tmp_path / "x.log", lines)
    reader = CandumpReader(str(path), block_size=7)
    items = list(reader)
    assert len(items) == 50
    bad = [i for i in items if isinstance(i, Event)]
    assert len(bad) == 1 and bad[0].fields["line"] == 34
    assert reader.stats["lines"] == 50
    assert reader.position_bytes == reader.size_bytes == path.stat().st_size


def test_reader_crlf_and_missing_final_newline(tmp_path: Path) -> None:
    path = tmp_path / "crlf.log"
    path.write_bytes(b"(1.0) can0 123#11 R\r\n(2.0) can0 123#22\r\n(3.0) can0 123#33")
    frames: list[Any] = list(CandumpReader(str(path), block_size=5))
    assert [f.data for f in frames] == [b"\x11", b"\x22", b"\x33"]
    assert frames[0].direction == "rx"


def test_gzip_log(tmp_path: Path) -> None:
    path = tmp_path / "flight.log.gz"
    with gzip.open(path, "wb") as f:
        f.write(b"(1.0) can0 00000F01#0F07000000000000\n" * 3)
    reader = open_input(str(path))
    assert len(list(reader)) == 3
    assert reader.position_bytes == path.stat().st_size


def test_python_can_writer_output_reads_the_same(tmp_path: Path) -> None:
    path = tmp_path / "pc.log"
    messages = [
        can.Message(timestamp=10.5, arbitration_id=0xF01, data=bytes(8)),
        can.Message(timestamp=10.6, arbitration_id=0x7FF, is_extended_id=False, data=b"\x01"),
        can.Message(timestamp=10.7, arbitration_id=0x123, is_remote_frame=True, dlc=2),
        can.Message(timestamp=10.8, arbitration_id=0x123, is_fd=True, data=bytes(range(12))),
    ]
    with can.CanutilsLogWriter(str(path), channel="can0") as writer:
        for msg in messages:
            writer.on_message_received(msg)
    ours = list(open_input(str(path)))
    theirs = list(can.LogReader(str(path)))
    assert len(ours) == len(theirs) == 4
    for frame, msg in zip(ours, theirs, strict=True):
        assert isinstance(frame, CanFrame)
        assert frame.time == pytest.approx(msg.timestamp)
        assert frame.can_id == msg.arbitration_id
        assert frame.extended == msg.is_extended_id
        assert frame.is_remote == msg.is_remote_frame
        assert frame.is_fd == msg.is_fd
        if not frame.is_remote:
            assert frame.data == bytes(msg.data)


# -- properties ------------------------------------------------------------------------------

frames = st.builds(
    CanFrame,
    time=st.integers(0, 2_000_000_000_000_000).map(lambda us: us / 1e6),
    can_id=st.integers(0, 0x1FFFFFFF),
    data=st.binary(max_size=8),
    extended=st.just(True),
    channel=st.sampled_from(["can0", "vcan1", "slcan0"]),
    direction=st.sampled_from(["", "rx", "tx"]),
)


def log_line(frame: CanFrame) -> bytes:
    suffix = {"": "", "rx": " R", "tx": " T"}[frame.direction]
    return (
        f"({frame.time:.6f}) {frame.channel} {frame.can_id:08X}#{frame.data.hex().upper()}{suffix}"
    ).encode()


@given(st.lists(frames, max_size=20))
def test_written_frames_parse_back(frames_in: list[CanFrame]) -> None:
    items, parser = parse(*[log_line(f) for f in frames_in])
    assert len(items) == len(frames_in)
    for got, want in zip(items, frames_in, strict=True):
        assert got.can_id == want.can_id and got.data == want.data
        assert got.time == pytest.approx(want.time, abs=1e-6)
        assert got.direction == want.direction
    assert parser.stats["bad_lines"] == 0


line_parts = st.sampled_from(
    [b"(", b")", b" ", b"#", b"##", b"R", b"T", b"1.5", b"can0", b"030F0001", b"123", b"EB90",
     b"[8]", b"  ", b"\t", b"remote request", b"ERRORFRAME", b"'", b"_C", b"0F", b"\xff", b"-"]
)  # fmt: skip


@settings(max_examples=300, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.lists(
        st.one_of(st.binary(max_size=40), st.lists(line_parts, max_size=12).map(b"".join)),
        max_size=15,
    ),
    st.sampled_from([None, PROTOCOL_IDS]),
)
def test_arbitrary_lines_never_raise_and_are_accounted(
    lines: list[bytes], wanted: frozenset[int] | None
) -> None:
    lines = [line.replace(b"\n", b"") for line in lines]
    items, parser = parse(*lines, wanted_ids=wanted)
    assert_accounted(parser)
    assert parser.stats["lines"] == len(lines)
    diagnostics = [i for i in items if isinstance(i, Event)]
    assert len(diagnostics) + parser.bad_lines_not_shown == parser.stats["bad_lines"]
    returned = len(items) - len(diagnostics)
    assert returned + parser.stats["other_frames"] == parser.stats["frames"]
