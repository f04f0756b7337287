"""Chapter 2.3 UAV status and the whole decoder: CAN frames and streams in, events out."""

from __future__ import annotations

import json

import jsonschema
from hypothesis import given, settings
from hypothesis import strategies as st

from analyzer.protocol.codec import encode_command
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.feedback import encode_attitude, encode_ranging, segments
from analyzer.protocol.framing import wrap_can, wrap_control
from analyzer.protocol.ids import (
    ALTITUDE_ID,
    CONTROL_ID,
    FEEDBACK_ID,
    GPS_ID,
    PROTOCOL_IDS,
    TEXT_END_ID,
    TEXT_ID,
    UAV_ATTITUDE_ID,
)
from analyzer.protocol.schema import topic_schemas
from analyzer.protocol.types import FROM_IDU, TO_IDU, CanFrame, Event, StreamChunk
from analyzer.protocol.uav import decode_status, encode_altitude, encode_gps, encode_text

SCHEMAS = topic_schemas()


def check_contract(events: list[Event]) -> None:
    """Every event is one JSON object that its topic's schema accepts."""
    for event in events:
        obj = json.loads(json.dumps(event.to_dict()))
        jsonschema.validate(obj, SCHEMAS[obj["topic"]])


def frame(can_id: int, data: bytes, t: float = 1.0, **kw: object) -> CanFrame:
    return CanFrame(t, can_id, data, channel="can0", **kw)  # type: ignore[arg-type]


def test_gps_example_of_the_document() -> None:
    data = bytes.fromhex("07 10 8D 12 87 35 68 46")  # lat 0x128D1007, lon 0x46683587
    fields, warnings = decode_status(GPS_ID, data)
    assert fields == {"latitude_deg": 31.1234567, "longitude_deg": 118.1234567}
    assert warnings == []
    assert encode_gps(31.1234567, 118.1234567) == data


def test_altitude_example_of_the_document() -> None:
    data = bytes.fromhex("F6 C5 00 00 00 00 00 00")
    assert decode_status(ALTITUDE_ID, data)[0] == {"altitude_m": 506.78}
    assert encode_altitude(506.78) == data


def test_uav_attitude_and_flags() -> None:
    data = bytes.fromhex("E8 03 18 FC 50 46 00 00")
    assert decode_status(UAV_ATTITUDE_ID, data)[0] == {
        "pitch_deg": 10.0, "roll_deg": -10.0, "yaw_deg": 180.0}  # fmt: skip
    _, warnings = decode_status(UAV_ATTITUDE_ID, data[:6] + b"\x01\x00")
    assert warnings == ["unused bytes 6-7 are not zero: 01 00"]
    _, warnings = decode_status(
        GPS_ID, encode_gps(0, 0)[:4] + (2_000_000_000).to_bytes(4, "little")
    )
    assert "longitude_deg: 200.0000000 deg out of range" in warnings[0]


def test_text_message_is_reassembled() -> None:
    dec = ProtocolDecoder()
    events: list[Event] = []
    for i, (can_id, data) in enumerate(encode_text("Low battery: return to home")):
        events += dec.feed(frame(can_id, data, 1.0 + i / 100))
    assert [e.topic for e in events] == ["/uav/text"]
    assert events[0].fields["text"] == "Low battery: return to home"
    assert events[0].fields["frames"] == 4
    check_contract(events)


def test_text_that_never_ends_is_reported() -> None:
    dec = ProtocolDecoder(text_limit=64)
    events: list[Event] = []
    for i in range(9):
        events += dec.feed(frame(TEXT_ID, b"ABCDEFGH", float(i)))
    assert [e.fields["kind"] for e in events] == ["text_unterminated"]
    events = dec.feed(frame(TEXT_ID, b"rest....", 20.0)) + dec.close(21.0)
    assert [e.fields["kind"] for e in events] == ["text_unterminated"]
    check_contract(events)


def test_every_topic_from_can() -> None:
    dec = ProtocolDecoder()
    items: list[CanFrame] = [frame(CONTROL_ID, encode_command("look_down"), 1.0)]
    items += [
        frame(FEEDBACK_ID, s, 1.1) for s in segments(encode_attitude(pitch_deg=-30, yaw_deg=90))
    ]
    items += [
        frame(FEEDBACK_ID, s, 1.2)
        for s in segments(
            encode_ranging(distance_m=250.5, height_m=30, latitude_deg=31.5, longitude_deg=118.25)
        )
    ]
    items += [frame(GPS_ID, encode_gps(31.1, 118.2), 1.3),
              frame(ALTITUDE_ID, encode_altitude(120.5), 1.3),
              frame(UAV_ATTITUDE_ID, bytes(8), 1.3),
              frame(TEXT_END_ID, b"hi\0\0\0\0\0\0", 1.4),
              frame(0x123, b"\x01", 1.5)]  # fmt: skip
    events = [e for item in items for e in dec.feed(item)] + dec.close()
    assert [e.topic for e in events] == [
        "/gimbal/command", "/gimbal/attitude", "/gimbal/ranging", "/uav/gps", "/uav/altitude",
        "/uav/attitude", "/uav/text"]  # fmt: skip
    assert events[1].fields["pitch_deg"] == -30.0
    assert events[2].fields["distance_m"] == 250.5
    assert all(e.source == "can0" and e.warnings == [] for e in events)
    assert dec.other_frames == 1
    check_contract(events)


def test_foreign_frames_on_request_and_bad_frames() -> None:
    dec = ProtocolDecoder(emit_other=True)
    other = dec.feed(frame(0x18FF50E5, b"\x01\x02", 1.0))
    assert other[0].topic == "/can/other" and other[0].fields["data"] == "01 02"
    remote = dec.feed(frame(CONTROL_ID, b"", 1.0, is_remote=True))
    assert remote[0].fields["kind"] == "bad_frame"
    error = dec.feed(frame(0x20000004, bytes(8), 1.0, is_error=True))
    assert error[0].fields["kind"] == "bus_error"
    std = dec.feed(frame(CONTROL_ID, encode_command("forward"), 1.0, extended=False))
    assert std[0].fields["name"] == "forward" and "standard (11-bit)" in std[0].warnings[0]
    check_contract(remote + error + std)


def test_tcp_stream_both_directions() -> None:
    dec = ProtocolDecoder()
    to_idu = wrap_control(encode_command("gimbal_control", pan_speed_dps=80)) + wrap_can(
        GPS_ID, encode_gps(31.1234567, 118.1234567)
    )
    from_idu = encode_attitude(pitch_deg=12.5, yaw_deg=180)
    events = dec.feed(StreamChunk(5.0, to_idu[:30], "tcp", TO_IDU))
    events += dec.feed(StreamChunk(5.1, from_idu[:20], "tcp", FROM_IDU))
    events += dec.feed(StreamChunk(5.2, to_idu[30:], "tcp", TO_IDU))
    events += dec.feed(StreamChunk(5.3, from_idu[20:], "tcp", FROM_IDU))
    assert [(e.topic, e.fields["direction"], e.time) for e in events] == [
        ("/gimbal/command", "gs_to_idu", 5.0),
        ("/uav/gps", "gs_to_idu", 5.2),
        ("/gimbal/attitude", "idu_to_gs", 5.3),
    ]
    assert events[0].fields["pan_speed_dps"] == 80.0
    assert events[1].fields["crc_set"] is False
    check_contract(events)
    stats = dec.stats
    assert stats["bytes_fed"] == stats["bytes_framed"] == len(to_idu) + len(from_idu)


def test_documents_look_down_example_on_tcp() -> None:
    dec = ProtocolDecoder()
    doc = bytes.fromhex(
        "EB 90 0A 00 00 00 00 00 00 00 00 00 00 40 88 0F 07 00 00 00 00 00 00 68 5e"
    )
    fixed = bytes.fromhex("EB 90 0A 00 00 00 00 00 00 00 00 00 40 88 0F 07 00 00 00 00 00 00 68 5E")
    events = dec.feed(StreamChunk(1.0, doc + fixed, "tcp", TO_IDU)) + dec.close()
    assert [e.topic for e in events] == ["/diagnostics", "/diagnostics", "/gimbal/command"]
    assert events[0].fields["kind"] == "crc_mismatch"
    assert events[2].fields["name"] == "look_down"
    check_contract(events)


def test_feedback_faults_on_can_become_diagnostics() -> None:
    dec = ProtocolDecoder()
    good = segments(encode_attitude(pitch_deg=1, yaw_deg=2))
    corrupt = [good[0], good[1], b"\xff" * 8, good[3]]
    events: list[Event] = []
    for i, seg in enumerate([*corrupt, good[0], good[1], good[3], *good, good[0]]):
        events += dec.feed(frame(FEEDBACK_ID, seg, i * 0.01))
    events += dec.close()
    assert [e.fields.get("kind", e.topic) for e in events] == [
        "crc_mismatch", "incomplete", "/gimbal/attitude", "incomplete"]  # fmt: skip
    check_contract(events)
    stats = dec.stats
    assert stats["bytes_framed"] + stats["bytes_discarded"] == stats["bytes_fed"]


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(
    st.sampled_from([*sorted(PROTOCOL_IDS), 0x7FF]),
    st.binary(max_size=9),
    st.booleans(),
), max_size=40))  # fmt: skip
def test_decoder_never_raises_on_any_can_frames(frames: list[tuple[int, bytes, bool]]) -> None:
    dec = ProtocolDecoder(emit_other=True)
    events: list[Event] = []
    for i, (can_id, data, remote) in enumerate(frames):
        events += dec.feed(CanFrame(i * 0.1, can_id, data, is_remote=remote and i % 5 == 0))
    events += dec.close()
    for e in events:
        json.dumps(e.to_dict())
    stats = dec.stats
    assert stats["bytes_framed"] + stats["bytes_discarded"] == stats["bytes_fed"]


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.binary(max_size=60), st.booleans()), max_size=20))
def test_decoder_never_raises_on_any_stream_bytes(chunks: list[tuple[bytes, bool]]) -> None:
    dec = ProtocolDecoder()
    for i, (data, up) in enumerate(chunks):
        dec.feed(StreamChunk(float(i), data, "tcp", TO_IDU if up else FROM_IDU))
    dec.close()
    stats = dec.stats
    assert stats["bytes_fed"] == sum(len(d) for d, _ in chunks)
    assert stats["bytes_framed"] + stats["bytes_discarded"] == stats["bytes_fed"]
