"""Chapter 3: TCP / UART framing, the erratum of docs/protocol-notes.md, splits, glue and garbage."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from analyzer.protocol.codec import encode_command
from analyzer.protocol.feedback import encode_attitude, encode_ranging
from analyzer.protocol.framing import RawFrame, StreamFramer, wrap_can, wrap_control
from analyzer.protocol.ids import GPS_ID
from analyzer.protocol.types import Event

LOOK_DOWN = bytes.fromhex("EB 90 0A 00 00 00 00 00 00 00 00 00 40 88 0F 07 00 00 00 00 00 00 68 5E")
LOOK_DOWN_DOC = bytes.fromhex(  # the document's version: one zero byte too many
    "EB 90 0A 00 00 00 00 00 00 00 00 00 00 40 88 0F 07 00 00 00 00 00 00 68 5e"
)
PAN_80 = bytes.fromhex("EB 90 0A 00 00 00 00 00 00 00 00 00 40 88 0F 04 40 1F 00 00 00 00 C0 5C")
GPS_DOC = bytes.fromhex("EB 90 0B 00 00 FF 15 00 00 00 00 00 40 88 07 10 8D 12 87 35 68 46 00 00")
ALTITUDE_DOC = bytes.fromhex(
    "EB 90 0B 00 00 FF 16 00 00 00 00 00 40 88 f6 c5 00 00 00 00 00 00 00 00"
)


def run(framer: StreamFramer, *chunks: bytes) -> list[RawFrame | Event]:
    out: list[RawFrame | Event] = []
    for i, chunk in enumerate(chunks):
        out += framer.feed(chunk, float(i))
    return out + framer.close(float(len(chunks)))


def summary(results: list[RawFrame | Event]) -> list[str]:
    return [f"frame {r.frame_type:02X}" if isinstance(r, RawFrame) else r.fields["kind"]
            for r in results]  # fmt: skip


def test_wrap_control_builds_the_checked_frames() -> None:
    assert wrap_control(encode_command("look_down")) == LOOK_DOWN
    assert wrap_control(encode_command("gimbal_control", pan_speed_dps=80)) == PAN_80


def test_wrap_can_builds_the_document_examples() -> None:
    assert wrap_can(GPS_ID, bytes.fromhex("07 10 8D 12 87 35 68 46")) == GPS_DOC
    assert wrap_can(0x0000FF16, bytes.fromhex("F6 C5 00 00 00 00 00 00")) == ALTITUDE_DOC


def test_corrected_look_down_frame_is_accepted() -> None:
    out = run(StreamFramer("tcp"), LOOK_DOWN)
    assert summary(out) == ["frame 0A"]


def test_documents_25_byte_look_down_is_reported_bad() -> None:
    f = StreamFramer("tcp")
    out = run(f, LOOK_DOWN_DOC)
    assert summary(out) == ["crc_mismatch", "garbage"]
    detail = out[0].fields["detail"]  # type: ignore[union-attr]
    assert "marker 40 88 at offset 13 instead of 12" in detail
    assert f.bytes_discarded == 25 and f.bytes_framed == 0


def test_uncalibrated_crc_of_0x0b_frames_is_accepted_but_a_wrong_one_is_not() -> None:
    out = run(StreamFramer("tcp"), GPS_DOC + ALTITUDE_DOC)
    assert summary(out) == ["frame 0B", "frame 0B"]
    assert all(isinstance(r, RawFrame) and not r.crc_set for r in out)
    assert summary(run(StreamFramer("tcp"), wrap_can(GPS_ID, bytes(8), with_crc=True))) == [
        "frame 0B"
    ]
    wrong = GPS_DOC[:-2] + b"\x12\x34"
    assert summary(run(StreamFramer("tcp"), wrong)) == ["crc_mismatch"]


def test_frames_split_across_reads_glued_and_with_garbage() -> None:
    stream = b"\x00\x11" + LOOK_DOWN + PAN_80 + b"\xeb\xeb\x90\x99junk" + LOOK_DOWN
    for cut in range(1, len(stream)):
        f = StreamFramer("uart")
        out = run(f, stream[:cut], stream[cut:])
        assert [s for s in summary(out) if s.startswith("frame")] == ["frame 0A"] * 3
        assert f.bytes_framed == 3 * 24
        assert f.bytes_framed + f.bytes_discarded == len(stream)


def test_byte_by_byte_feeding() -> None:
    stream = PAN_80 + b"zz" + LOOK_DOWN
    f = StreamFramer("uart")
    out = run(f, *[bytes([b]) for b in stream])
    assert summary(out) == ["frame 0A", "garbage", "frame 0A"]


def test_truncated_frame_followed_by_a_frame() -> None:
    f = StreamFramer("tcp")
    out = run(f, LOOK_DOWN[:15] + PAN_80)
    assert summary(out) == ["incomplete", "frame 0A"]


def test_feedback_frames_with_and_without_padding() -> None:
    attitude = encode_attitude(pitch_deg=5, yaw_deg=6)
    ranging = encode_ranging(distance_m=1, height_m=2, latitude_deg=3, longitude_deg=4)
    f = StreamFramer("tcp")
    out = run(f, attitude + ranging[:31] + LOOK_DOWN + attitude[:27])
    assert summary(out) == ["frame 0C", "frame 10", "frame 0A", "frame 0C"]
    assert f.bytes_framed == f.bytes_fed


def test_damaged_feedback_frame_takes_its_padding_along() -> None:
    attitude = bytearray(encode_attitude(pitch_deg=5, yaw_deg=6))
    attitude[20] ^= 0x01
    f = StreamFramer("tcp")
    out = run(f, bytes(attitude) + LOOK_DOWN)
    assert summary(out) == ["crc_mismatch", "frame 0A"]
    assert out[0].fields["byte_count"] == 32  # type: ignore[union-attr]


def test_stream_ending_inside_a_frame_is_incomplete() -> None:
    f = StreamFramer("tcp")
    out = run(f, LOOK_DOWN[:10])
    assert summary(out) == ["incomplete"]
    assert f.bytes_discarded == 10


def test_long_garbage_is_reported_in_bounded_pieces() -> None:
    f = StreamFramer("tcp")
    out = run(f, bytes(range(1, 200)) * 50)
    assert all(r.fields["kind"] == "garbage" for r in out if isinstance(r, Event))
    assert sum(r.fields["byte_count"] for r in out if isinstance(r, Event)) == 199 * 50
    assert all(len(r.fields["raw"]) <= 64 * 3 for r in out if isinstance(r, Event))


FRAMES = [LOOK_DOWN, PAN_80, GPS_DOC, encode_attitude(pitch_deg=1, yaw_deg=1)]


@settings(max_examples=300, deadline=None)
@given(
    st.lists(st.one_of(st.binary(max_size=40), st.sampled_from(FRAMES)), max_size=20),
    st.data(),
)
def test_arbitrary_bytes_never_raise_and_every_byte_is_accounted(
    pieces: list[bytes], data: st.DataObject
) -> None:
    stream = b"".join(pieces)
    cuts = sorted(data.draw(st.lists(st.integers(0, len(stream)), max_size=8)))
    chunks = [stream[a:b] for a, b in zip([0, *cuts], [*cuts, len(stream)], strict=True)]
    f = StreamFramer("tcp")
    out = run(f, *chunks)
    assert f.bytes_fed == len(stream)
    assert f.bytes_framed + f.bytes_discarded == len(stream)
    reported = sum(r.fields["byte_count"] for r in out if isinstance(r, Event))
    assert reported == f.bytes_discarded
    assert sum(len(r.data) for r in out if isinstance(r, RawFrame)) <= f.bytes_framed
