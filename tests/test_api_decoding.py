"""The Python API's sans-IO ``Decoder``: the protocol's vectors, a stream split at every byte,
and no exception whatever the bytes."""

from __future__ import annotations

import json

import can
from hypothesis import given, settings
from hypothesis import strategies as st

from analyzer import Decoder, Event, encode, status_message, tcp_frame
from analyzer.protocol.decoder import ProtocolDecoder as ProtocolDecoder
from analyzer.protocol.feedback import encode_ranging, segments
from analyzer.protocol.types import CanFrame
from tests.test_protocol_feedback import attitude_by_hand
from tests.test_protocol_framing import GPS_DOC, LOOK_DOWN, LOOK_DOWN_DOC, PAN_80

FEEDBACK_ID = 0x030F0001
CONTROL_ID = 0x00000F01


def dicts(events: list[Event]) -> list[dict[str, object]]:
    return [json.loads(json.dumps(e.to_dict(), default=str)) for e in events]


def test_a_command_frame_is_one_event_at_once() -> None:
    [event] = Decoder().feed_can(CONTROL_ID, bytes.fromhex("0F 04 0C FE 00 00 00 00"), 5.0, "can1")
    assert (event.topic, event.time, event.source) == ("/gimbal/command", 5.0, "can1")
    assert event.fields["name"] == "gimbal_control" and event.fields["pan_speed_dps"] == -5.0
    assert event.to_dict()["raw"] == "0F 04 0C FE 00 00 00 00" and event.warnings == []


def test_feedback_is_reassembled_from_its_four_segments_and_crc_checked() -> None:
    decoder = Decoder()
    message = attitude_by_hand()  # chapter 2.2's table, built by hand
    parts = segments(message)
    assert [
        decoder.feed_can(FEEDBACK_ID, part, 1.0 + i / 100) for i, part in enumerate(parts[:3])
    ] == [[], [], []]
    [event] = decoder.feed_can(FEEDBACK_ID, parts[3], 1.03)
    assert event.topic == "/gimbal/attitude" and event.time == 1.03
    assert (event.fields["pitch_deg"], event.fields["yaw_deg"], event.fields["motor_yaw_deg"]) == (
        -45.0,
        270.0,
        12.34,
    )
    assert event.fields["control_mode"] == "locking" and event.fields["control_mode_code"] == 3
    # one bit flipped: a crc_mismatch diagnostic, no attitude
    damaged = bytearray(message)
    damaged[20] ^= 0x01
    events = [
        e
        for i, p in enumerate(segments(bytes(damaged)))
        for e in decoder.feed_can(FEEDBACK_ID, p, 2 + i / 100)
    ]
    assert [(e.topic, e.fields["kind"]) for e in events] == [("/diagnostics", "crc_mismatch")]
    # a segment lost: the message is incomplete (said when the next one begins, or at the end)
    events = [e for p in parts[:2] for e in decoder.feed_can(FEEDBACK_ID, p, 3.0)] + decoder.close()
    assert [(e.topic, e.fields["kind"]) for e in events] == [("/diagnostics", "incomplete")]


def test_the_uav_status_frames_and_a_text_message() -> None:
    decoder = Decoder()
    gps = status_message("gps", latitude_deg=31.1234567, longitude_deg=118.1234567)
    [event] = decoder.feed_message(gps)
    assert event.topic == "/uav/gps" and event.fields["latitude_deg"] == 31.1234567
    [event] = decoder.feed_can(0xFF16, bytes.fromhex("F6 C5 00 00 00 00 00 00"), 1.0)
    assert event.fields["altitude_m"] == 506.78
    text = b"Low battery"
    assert decoder.feed_can(0x02008201, text[:8], 2.0) == []
    [event] = decoder.feed_can(0x02008202, text[8:].ljust(8, b"\0"), 2.1)
    assert event.topic == "/uav/text" and event.fields["text"] == "Low battery"


def test_it_is_the_decoder_every_command_runs() -> None:
    frames = [
        CanFrame(1.0 + i / 100, FEEDBACK_ID, part, channel="can0")
        for i, part in enumerate(segments(attitude_by_hand()))
    ]
    frames.append(CanFrame(2.0, CONTROL_ID, encode("look_down"), channel="can0"))
    frames.append(CanFrame(2.5, 0x18FEF100, bytes(8), channel="can0"))  # another device
    inner = ProtocolDecoder(emit_other=True)
    public = Decoder(other_frames=True)
    expected = [e for f in frames for e in inner.feed_can(f)]
    got = [e for f in frames for e in public.feed_can(f.can_id, f.data, f.time, f.channel)]
    assert dicts(got) == dicts(expected) and len(got) == 3
    assert got[-1].topic == "/can/other"
    assert Decoder().feed_can(0x18FEF100, bytes(8), 2.5) == []  # other devices: not by default


# Chapter 3's frames (the look-down as corrected, pan 80, the TTL GPS frame), a feedback
# message in the same framing, and commands built by the API.
STREAM = b"".join(
    [
        LOOK_DOWN,
        PAN_80,
        GPS_DOC,
        attitude_by_hand(),
        encode_ranging(distance_m=12.5, height_m=3.0, latitude_deg=31.1, longitude_deg=118.1),
        tcp_frame("specified_angle", yaw_deg=45),
        tcp_frame("tracking", x=4096, y=4096, width=320, height=240),
    ]
)


def stream_events(*chunks: bytes) -> list[dict[str, object]]:
    decoder = Decoder()
    events = [e for chunk in chunks for e in decoder.feed_stream(chunk, 7.0, source="idu")]
    return dicts(events + decoder.close())


def test_a_stream_split_at_every_byte_gives_the_same_events() -> None:
    whole = stream_events(STREAM)
    assert [e["topic"] for e in whole] == [
        "/gimbal/command", "/gimbal/command", "/uav/gps", "/gimbal/attitude", "/gimbal/ranging",
        "/gimbal/command", "/gimbal/command",
    ]  # fmt: skip
    assert all(e["warnings"] == [] and e["source"] == "idu" for e in whole)
    for cut in range(1, len(STREAM)):
        assert stream_events(STREAM[:cut], STREAM[cut:]) == whole, cut
    assert stream_events(*(STREAM[i : i + 1] for i in range(len(STREAM)))) == whole


def test_the_documents_25_byte_look_down_is_flagged_not_accepted() -> None:
    events = stream_events(LOOK_DOWN_DOC + PAN_80)
    assert [e["topic"] for e in events if e["topic"] != "/diagnostics"] == ["/gimbal/command"]
    assert events[-1]["name"] == "gimbal_control"  # resynchronised on the next header
    assert any(e["topic"] == "/diagnostics" for e in events)


def test_python_can_messages_of_every_kind() -> None:
    decoder = Decoder()
    remote = can.Message(arbitration_id=CONTROL_ID, is_remote_frame=True, dlc=8, channel="vcan0")
    [event] = decoder.feed_message(remote)
    assert event.fields["kind"] == "bad_frame" and event.source == "vcan0"
    error = can.Message(arbitration_id=0x20000004, is_error_frame=True, data=bytes(8), dlc=8)
    assert [e.fields["kind"] for e in decoder.feed_message(error) if e.topic == "/diagnostics"] == [
        "bus_error"
    ]
    standard = can.Message(arbitration_id=0x701, is_extended_id=False, data=bytes(8))
    assert decoder.feed_message(standard) == []


@settings(max_examples=200, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.sampled_from(
                [CONTROL_ID, FEEDBACK_ID, 0xFF15, 0xFF16, 0xFF13, 0x02008201, 0x02008202]
            )
            | st.integers(0, 0x1FFFFFFF),
            st.binary(max_size=12),
            st.floats(allow_nan=False, allow_infinity=False),
        ),
        max_size=30,
    ),
    st.lists(
        st.binary(max_size=40) | st.sampled_from([LOOK_DOWN, PAN_80, GPS_DOC, attitude_by_hand()]),
        max_size=12,
    ),
)
def test_no_bytes_make_it_raise(
    frames: list[tuple[int, bytes, float]], pieces: list[bytes]
) -> None:
    decoder = Decoder(other_frames=True)
    events: list[Event] = []
    for can_id, data, t in frames:
        events += decoder.feed_can(can_id, data, t)
    for i, piece in enumerate(pieces):
        events += decoder.feed_stream(piece, float(i))
    events += decoder.tick(1e9) + decoder.close()
    for event in events:
        json.dumps(event.to_dict(), default=str)  # every event is one JSON line
