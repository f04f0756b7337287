"""Chapter 2.2: feedback messages, and their reassembly from four CAN segments."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from analyzer.protocol.crc import crc_bytes
from analyzer.protocol.feedback import (
    decode_feedback,
    encode_attitude,
    encode_ranging,
    segments,
)
from analyzer.protocol.reassembly import FeedbackReassembler, Message
from analyzer.protocol.types import Event

# An attitude message built by hand from the table of chapter 2.2:
# type 1, not tracking, mode 3, pitch -45.00, yaw 270.00, motor yaw 12.34.
ATTITUDE_HEX = "EB 90 0C 00 00 00 00 00 00 00 00 00 21 FE 0F 01 01 00 03 6C EE 78 69 D2 04"


def attitude_by_hand() -> bytes:
    body = bytes.fromhex(ATTITUDE_HEX)
    return body + crc_bytes(body) + bytes(5)


def test_attitude_layout_by_hand() -> None:
    message = attitude_by_hand()
    assert len(message) == 32
    layout, fields, warnings = decode_feedback(message)
    assert layout is not None and layout.topic == "/gimbal/attitude"
    assert warnings == []
    assert fields["pitch_deg"] == -45.0
    assert fields["yaw_deg"] == 270.0
    assert fields["motor_yaw_deg"] == 12.34
    assert fields["gimbal_type_code"] == 1 and fields["gimbal_type"].startswith("35x")
    assert fields["tracking"] is False
    assert fields["control_mode_code"] == 3 and fields["control_mode"] == "locking"
    assert encode_attitude(pitch_deg=-45, yaw_deg=270, motor_yaw_deg=12.34) == message


def test_yaw_is_unsigned_up_to_360() -> None:
    message = encode_attitude(pitch_deg=0, yaw_deg=359.99)
    assert decode_feedback(message)[1]["yaw_deg"] == 359.99


def test_ranging_layout_with_one_padding_byte() -> None:
    message = encode_ranging(distance_m=1234.5, height_m=-12.3, latitude_deg=31.1234567,
                             longitude_deg=118.1234567)  # fmt: skip
    assert len(message) == 32 and message[2] == 0x10 and message[31] == 0
    assert message[21:25] == bytes.fromhex("87 35 68 46")  # longitude first, at 21
    assert message[25:29] == bytes.fromhex("07 10 8D 12")  # latitude at 25
    layout, fields, warnings = decode_feedback(message)
    assert layout is not None and layout.topic == "/gimbal/ranging" and warnings == []
    assert fields == {"success": True, "distance_m": 1234.5, "height_m": -12.3,
                      "longitude_deg": 118.1234567, "latitude_deg": 31.1234567}  # fmt: skip


def test_attitude_out_of_range_and_motor_limits_by_type() -> None:
    message = encode_attitude(pitch_deg=-100, yaw_deg=0, motor_yaw_deg=200, gimbal_type=1)
    _, fields, warnings = decode_feedback(message)
    assert fields["motor_yaw_deg"] == 200.0
    assert any("motor_yaw_deg" in w and "170" in w for w in warnings)
    wide = encode_attitude(pitch_deg=0, yaw_deg=0, motor_yaw_deg=300, gimbal_type=3)
    assert decode_feedback(wide)[2] == []
    steep = encode_attitude(pitch_deg=-120, yaw_deg=0, check_range=False)
    assert "pitch_deg: -120.00 deg out of range [-110.00, 60.00] deg" in decode_feedback(steep)[2]


def feed_all(r: FeedbackReassembler, parts: list[bytes], t0: float = 0.0,
             step: float = 0.001) -> list[Message | Event]:  # fmt: skip
    out: list[Message | Event] = []
    for i, part in enumerate(parts):
        out += r.feed(part, t0 + i * step)
    return out


def kinds(results: list[Message | Event]) -> list[str]:
    return ["message" if isinstance(x, Message) else x.fields["kind"] for x in results]


def test_four_segments_make_one_message() -> None:
    r = FeedbackReassembler("can0")
    out = feed_all(r, segments(attitude_by_hand()))
    assert kinds(out) == ["message"]
    assert isinstance(out[0], Message) and out[0].data == attitude_by_hand()
    assert out[0].time == 0.003


def test_dropped_segment_is_reported_and_next_message_decodes() -> None:
    a, b = segments(attitude_by_hand()), segments(encode_attitude(pitch_deg=1, yaw_deg=2))
    r = FeedbackReassembler("can0")
    out = feed_all(r, [a[0], a[1], a[3], *b])
    assert kinds(out) == ["incomplete", "message"]
    assert out[0].fields["segments"] == 3  # type: ignore[union-attr]
    assert r.bytes_framed + r.bytes_discarded == r.bytes_fed


def test_lost_first_segment_is_reported() -> None:
    a, b = segments(attitude_by_hand()), segments(attitude_by_hand())
    r = FeedbackReassembler("can0")
    assert kinds(feed_all(r, [*a[1:], *b])) == ["incomplete", "message"]


def test_repeated_segment_is_reported_and_message_kept() -> None:
    a, b = segments(attitude_by_hand()), segments(attitude_by_hand())
    r = FeedbackReassembler("can0")
    out = feed_all(r, [a[0], a[1], a[2], a[2], a[3], *b])
    assert kinds(out) == ["duplicate", "message", "message"]
    assert r.bytes_framed + r.bytes_discarded == r.bytes_fed


def test_two_repeats_in_one_message() -> None:
    a, b = segments(attitude_by_hand()), segments(attitude_by_hand())
    r = FeedbackReassembler("can0")
    out = feed_all(r, [a[0], a[1], a[1], a[2], a[2], a[3], *b])
    assert kinds(out) == ["duplicate", "duplicate", "message", "message"]
    assert isinstance(out[2], Message)
    assert out[2].warnings == ("segment 2 was repeated", "segment 3 was repeated")


def test_a_lone_last_segment_long_after_is_no_repeat() -> None:
    # A gimbal at rest sends identical messages; if the next one loses its first
    # three segments, what is left equals the last segment but comes 500 ms later.
    a = segments(attitude_by_hand())
    r = FeedbackReassembler("can0")
    out = feed_all(r, a, 0.0) + r.feed(a[3], 0.5) + feed_all(r, a, 1.0)
    assert kinds(out) == ["message", "incomplete", "message"]


def test_repeated_last_segment_is_a_duplicate() -> None:
    a, b = segments(attitude_by_hand()), segments(attitude_by_hand())
    r = FeedbackReassembler("can0")
    out = feed_all(r, [*a, a[3], *b])
    assert kinds(out) == ["message", "duplicate", "message"]
    assert r.bytes_framed + r.bytes_discarded == r.bytes_fed


def test_corrupted_segment_is_a_crc_mismatch() -> None:
    a = segments(attitude_by_hand())
    bad = bytes([a[2][0] ^ 0x40]) + a[2][1:]
    r = FeedbackReassembler("can0")
    out = feed_all(r, [a[0], a[1], bad, a[3]])
    assert kinds(out) == ["crc_mismatch"]
    assert "CRC" in out[0].fields["detail"]  # type: ignore[union-attr]


def test_header_inside_payload_is_no_false_start() -> None:
    # g_type 0xEB, trace_flag 0x90, mode 0x0C: segment 3 starts with EB 90 0C.
    message = encode_attitude(pitch_deg=1, yaw_deg=2, gimbal_type=0xEB, control_mode=0x0C,
                              tracking=True, check_range=False)  # fmt: skip
    message = message[:17] + b"\x90" + message[18:25]
    message = message + crc_bytes(message) + bytes(5)
    parts = segments(message)
    assert parts[2][:3] == b"\xeb\x90\x0c"
    r = FeedbackReassembler("can0")
    out = feed_all(r, parts)
    assert kinds(out) == ["message"]


def test_header_inside_payload_after_a_lost_segment() -> None:
    tricky = encode_ranging(distance_m=1, height_m=1, latitude_deg=0, longitude_deg=0)
    tricky = tricky[:24] + b"\xeb\x90\x10\x00\x00" + tricky[29:]  # segment 4 looks like a header
    tricky = tricky[:29] + crc_bytes(tricky[:29]) + b"\x00"
    a, b = segments(tricky), segments(attitude_by_hand())
    r = FeedbackReassembler("can0")
    assert kinds(feed_all(r, [a[0], a[1], a[2], a[3], *b])) == ["message", "message"]
    r = FeedbackReassembler("can0")
    out = feed_all(r, [a[0], a[2], a[3], *b])  # segment 2 lost
    assert kinds(out)[-1] == "message"
    assert "message" not in kinds(out)[:-1]
    assert r.bytes_framed + r.bytes_discarded == r.bytes_fed


def test_late_segment_is_flagged_and_stale_partial_is_given_up() -> None:
    a = segments(attitude_by_hand())
    r = FeedbackReassembler("can0")
    out = r.feed(a[0], 0.0) + r.feed(a[1], 0.01) + r.feed(a[2], 0.5) + r.feed(a[3], 0.51)
    assert isinstance(out[0], Message)
    assert out[0].warnings == ("late segment: 490 ms between segments",)
    r = FeedbackReassembler("can0")
    assert r.feed(a[0], 0.0) + r.feed(a[1], 0.01) == []
    assert kinds(r.tick(0.5)) == []
    assert kinds(r.tick(2.0)) == ["incomplete"]
    assert kinds(r.feed(a[0], 3.0) + r.close(3.1)) == ["incomplete"]


@settings(max_examples=300, deadline=None)
@given(st.lists(st.one_of(
    st.binary(min_size=0, max_size=8),
    st.sampled_from(segments(attitude_by_hand()) + segments(
        encode_ranging(distance_m=5, height_m=5, latitude_deg=1, longitude_deg=2))),
), max_size=40))  # fmt: skip
def test_any_segment_sequence_never_raises_and_accounts_for_every_byte(parts: list[bytes]) -> None:
    r = FeedbackReassembler("can0")
    out = feed_all(r, parts) + r.close(99.0)
    fed = sum(len(p) for p in parts)
    assert r.bytes_fed == fed
    assert r.bytes_framed + r.bytes_discarded == fed
    framed = sum(len(x.data) for x in out if isinstance(x, Message))
    reported = sum(x.fields["byte_count"] for x in out if isinstance(x, Event))
    assert framed + reported == fed
    for x in out:
        if isinstance(x, Message):
            assert decode_feedback(x.data)[0] is not None
