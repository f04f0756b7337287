"""Readable event lines: columns, units in words, diagnostics and warnings, colour on request."""

from __future__ import annotations

import time
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from analyzer.protocol.codec import encode_command
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.feedback import encode_attitude, encode_ranging, segments
from analyzer.protocol.framing import wrap_control
from analyzer.protocol.ids import ALTITUDE_ID, FEEDBACK_ID, GPS_ID, UAV_ATTITUDE_ID
from analyzer.protocol.types import CRC_MISMATCH, CanFrame, Event, StreamChunk, diagnostic
from analyzer.protocol.uav import encode_altitude, encode_gps, encode_text, encode_uav_attitude
from analyzer.render import describe_event, format_time, render_event
from analyzer.timefmt import LOCAL, UTC

T = 1_700_000_000.25


def decode(*items: CanFrame | StreamChunk, emit_other: bool = False) -> list[Event]:
    decoder = ProtocolDecoder(emit_other=emit_other)
    return [e for item in items for e in decoder.feed(item)] + decoder.close()


def command(name: str, **params: Any) -> Event:
    (event,) = decode(CanFrame(T, 0xF01, encode_command(name, **params), channel="can0"))
    return event


def body(line: str) -> str:
    """The line after the fixed columns."""
    return line[UTC.clock_width + 1 + 17 + 1 + 17 + 1 + 16 + 1 :]


def test_command_line_has_aligned_columns_and_units_in_words() -> None:
    line = render_event(command("gimbal_control", pan_speed_dps=-5.0, tilt_speed_dps=0))
    assert line.startswith(format_time(T).rjust(12) + " can0 ")
    assert line[32:49] == "/gimbal/command  "
    assert line[50:66] == "gimbal_control  "
    assert body(line) == "pan -5.00 deg/s  tilt 0.00 deg/s"


def test_describe_event_is_the_words_without_columns() -> None:
    event = command("gimbal_control", pan_speed_dps=-5.0, tilt_speed_dps=0)
    assert describe_event(event) == "gimbal_control pan -5.00 deg/s  tilt 0.00 deg/s"


@pytest.mark.parametrize(
    ("name", "params", "words"),
    [
        ("specified_angle", {"yaw_deg": 45}, "yaw 45.00 deg  geodetic"),
        ("specified_angle", {"zoom": 10}, "zoom 10.00"),
        ("palette", {"palette": "iron_red"}, "dual_sensor  iron_red"),
        ("tracking", {"x": 100, "y": 200, "width": 32, "height": 48}, "x 100  y 200  width 32"),
        ("snapshot", {"mode": "time_lapse", "delay_s": 5}, "time_lapse  delay 5 s"),
        ("look_down", {}, ""),
    ],
)
def test_command_parameters(name: str, params: dict[str, object], words: str) -> None:
    line = render_event(command(name, **params))
    assert words in body(line)
    assert "_raw" not in line and "_code" not in line


def test_unknown_command_shows_its_bytes_and_warning() -> None:
    (event,) = decode(CanFrame(T, 0xF01, bytes.fromhex("0F77000000000000"), channel="can0"))
    line = render_event(event)
    assert " unknown " in line and "cmd 0x77" in line and "raw 0F 77 00" in line
    assert line.endswith("! unknown command CMD 0x77 for S_ID 0x0F")


def test_feedback_and_uav_lines() -> None:
    att = segments(encode_attitude(pitch_deg=-10.0, yaw_deg=100.0, motor_yaw_deg=5.0))
    rng = segments(
        encode_ranging(
            distance_m=123.4, height_m=20, latitude_deg=31.1234567, longitude_deg=118.1234567
        )
    )
    frames = [CanFrame(T, FEEDBACK_ID, s) for s in att + rng]
    frames += [
        CanFrame(T, GPS_ID, encode_gps(31.1234567, 118.1234567)),
        CanFrame(T, ALTITUDE_ID, encode_altitude(506.78)),
        CanFrame(T, UAV_ATTITUDE_ID, encode_uav_attitude(1.5, -2.25, 270)),
    ]
    frames += [CanFrame(T, cid, data) for cid, data in encode_text("takeoff")]
    lines = [body(render_event(e)) for e in decode(*frames)]
    assert "pitch -10.00 deg  yaw 100.00 deg  motor yaw 5.00 deg" in lines[0]
    assert "control mode locking" in lines[0] and "tracking no" in lines[0]
    assert "distance 123.40 m" in lines[1] and "latitude 31.1234567 deg" in lines[1]
    assert lines[2] == "latitude 31.1234567 deg  longitude 118.1234567 deg"
    assert lines[3] == "altitude 506.78 m"
    assert lines[4] == "pitch 1.50 deg  roll -2.25 deg  yaw 270.00 deg"
    assert lines[5] == "'takeoff'"


def test_stream_events_show_the_direction_and_the_client_port() -> None:
    chunk = StreamChunk(T, wrap_control(encode_command("look_down")), "uart", "gs_to_idu")
    (event,) = decode(chunk)
    assert " uart gs->idu " in render_event(event)
    flow = "tcp:10.0.0.5:50211-192.168.42.200:2000"
    (event,) = decode(StreamChunk(T, wrap_control(encode_command("look_down")), flow, "idu_to_gs"))
    line = render_event(event)
    assert " tcp:50211 idu->gs " in line and line.index("/gimbal/command") == 32
    (event,) = decode(StreamChunk(T, wrap_control(encode_command("forward")), flow + "#2", "x"))
    assert " tcp:50211#2 x " in render_event(event)


def test_other_frames() -> None:
    (event,) = decode(CanFrame(T, 0x123, b"\x01\x02", False, "can1"), emit_other=True)
    assert body(render_event(event)) == "id 0x123 [2] 01 02"


def test_diagnostics_stand_out_and_long_raw_is_cut() -> None:
    event = diagnostic(T, "can0", CRC_MISMATCH, "CRC 00 00 on the wire", bytes(range(40)))
    line = render_event(event)
    assert " CRC_MISMATCH " in line
    assert "raw 00 01 02" in line and "... (40 bytes)" in line and " 27" not in line


def test_colour_only_when_asked() -> None:
    event = diagnostic(T, "can0", CRC_MISMATCH, "bad", b"\x01")
    assert "\033[" not in render_event(event)
    coloured = render_event(event, color=True)
    assert "\033[1;31m" in coloured
    assert "\033[33m" in render_event(
        decode(CanFrame(T, 0xF01, bytes.fromhex("0F77000000000000")))[0], color=True
    )


def test_relative_times() -> None:
    assert format_time(12.3456) == "12.346"
    assert format_time(T) == time.strftime("%H:%M:%S", time.gmtime(int(T))) + ".250Z"


def test_local_time_shows_its_offset(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("TZ", "Europe/Berlin")
    time.tzset()
    try:
        assert format_time(1_715_680_801.253, LOCAL) == "12:00:01.253+02:00"
        assert len(format_time(1_715_680_801.253, LOCAL)) == LOCAL.clock_width
        assert LOCAL.format_datetime(1_715_680_801.253) == "2024-05-14 12:00:01.253+02:00"
        assert format_time(12.3456, LOCAL) == "12.346"
        assert UTC.format_datetime(1_715_680_801.253) == "2024-05-14 10:00:01.253Z"
    finally:
        monkeypatch.delenv("TZ")
        time.tzset()
    assert UTC.format_datetime(1_715_680_801.9996) == "2024-05-14 10:00:02.000Z"
    assert len(format_time(1_715_680_801.253)) == UTC.clock_width


@given(
    st.dictionaries(
        st.text(max_size=12),
        st.one_of(st.none(), st.booleans(), st.integers(), st.floats(), st.text(max_size=20)),
        max_size=6,
    ),
    st.sampled_from(["/gimbal/command", "/diagnostics", "/can/other", "/uav/text", "/x/y"]),
    st.lists(st.text(max_size=10), max_size=2),
)
def test_any_event_renders_on_one_line(
    fields: dict[str, object], topic: str, warnings: list[str]
) -> None:
    event = Event(topic, T, "src", dict(fields), warnings)
    for color in (False, True):
        line = render_event(event, color=color)
        assert isinstance(line, str)


def test_odd_field_types_do_not_break_a_line() -> None:
    event = Event("/can/other", T, "can0", {"can_id": "x", "dlc": None})
    assert "can_id x" in render_event(event)


def test_a_findings_moment_is_shown_as_a_clock_time_not_unix_seconds() -> None:
    finding = Event(
        "/analysis/response",
        T,
        "analysis",
        fields={"command": "look_down", "verdict": "unknown", "observed_at": T + 2.5},
    )
    words = describe_event(finding)
    assert f"observed at {format_time(T + 2.5)}" in words
    assert str(T + 2.5) not in words
