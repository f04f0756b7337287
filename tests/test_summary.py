"""The --summary accumulator: counts, time span, feedback rate and gaps, CRC error rate."""

from __future__ import annotations

import json

from analyzer.protocol.types import CRC_MISMATCH, INCOMPLETE, Event, diagnostic
from analyzer.summary import Summary

T0 = 1_700_000_000.0


def attitude(t: float, source: str = "can0", **extra: object) -> Event:
    return Event("/gimbal/attitude", t, source, {"yaw_deg": 1.0, **extra})


def test_feedback_rate_and_longest_gap() -> None:
    summary = Summary("f.log", "candump")
    times = [T0 + i * 0.5 for i in range(10)] + [T0 + 9.0, T0 + 9.5]  # a 4.5 s silence
    for t in times:
        summary.add(attitude(t))
    summary.add(Event("/gimbal/ranging", T0 + 10.0, "can0", {"distance_m": 1.0}))
    (track,) = summary.feedback.values()
    assert track.count == 13
    assert track.longest_gap == 4.5 and track.gap_end == T0 + 9.0
    assert track.rate_hz == 12 / 10.0
    text = summary.render()
    assert "13 messages, 1.20 Hz (expected about 2 Hz) OFF" in text
    assert "longest gap 4.500 s" in text


def test_feedback_is_tracked_per_source_and_direction() -> None:
    summary = Summary()
    for i in range(5):
        summary.add(attitude(T0 + i * 0.5))
        summary.add(attitude(T0 + i * 0.5, "tcp:1", direction="idu_to_gs", transport="stream"))
    assert set(summary.feedback) == {"can0", "tcp:1 idu_to_gs"}
    assert "feedback can0" in summary.render() and "2.00 Hz" in summary.render()


def test_crc_error_rate_counts_only_crc_protected_messages() -> None:
    summary = Summary()
    summary.add(attitude(T0))
    summary.add(Event("/gimbal/command", T0, "can0", {"name": "look_down"}))  # CAN: no CRC
    summary.add(Event("/gimbal/command", T0, "tcp", {"name": "forward", "transport": "stream"}))
    summary.add(Event("/uav/gps", T0, "tcp", {"transport": "stream", "crc_set": False}))
    summary.add(diagnostic(T0, "can0", CRC_MISMATCH, "bad"))
    summary.add(diagnostic(T0, "can0", INCOMPLETE, "lost"))
    assert summary.crc_checked == 2 and summary.crc_errors == 1
    assert summary.crc_error_rate == 1 / 3
    assert "1 of 3 CRC-protected messages (33.33 %)" in summary.render()
    assert summary.kinds == {CRC_MISMATCH: 1, INCOMPLETE: 1}
    assert summary.commands == {"look_down": 1, "forward": 1}


def test_time_span_includes_frames_without_events() -> None:
    summary = Summary()
    summary.add(attitude(T0 + 5))
    summary.finish(first_time=T0, last_time=T0 + 60, input_stats={"lines": 3, "frames": 3})
    assert summary.span == 60.0
    assert "(60.000 s)" in summary.render()


def test_empty_and_untimed_inputs() -> None:
    summary = Summary("x.bin", "stream")
    summary.finish()
    text = summary.render()
    assert "no timestamps" in text and "nothing read" in text
    assert "feedback       none" in text and "no CRC-protected messages" in text
    summary.add(Event("/gimbal/command", 0.0, "x.bin", {"name": "forward", "transport": "stream"}))
    assert "no timestamps" in summary.render()


def test_to_dict_is_json() -> None:
    summary = Summary("f.log", "candump")
    for i in range(3):
        summary.add(attitude(T0 + i * 0.5, warnings_ignored=True))
    summary.add(Event("/gimbal/command", T0, "can0", {"name": "unknown"}, ["unknown command"]))
    summary.finish(input_stats={"lines": 4}, decoder_stats={"frames": 4})
    obj = json.loads(json.dumps(summary.to_dict()))
    assert obj["events"] == 4 and obj["events_with_warnings"] == 1
    assert obj["feedback"]["can0"]["rate_hz"] == 2.0
    assert obj["crc_error_rate"] == 0.0
    assert obj["input"] == {"lines": 4}


def test_colour_marks_problems() -> None:
    summary = Summary()
    summary.add(diagnostic(T0, "can0", CRC_MISMATCH, "bad"))
    assert "\033[1;31m" in summary.render(color=True)
    assert "\033[" not in summary.render()
