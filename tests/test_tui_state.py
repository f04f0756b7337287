"""The monitor's UI-free parts: screen model, filter, bridge and wording."""

from __future__ import annotations

import threading

import pytest

from analyzer.pipeline import Batch, RawItem
from analyzer.protocol.codec import encode_command
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.feedback import encode_attitude, segments
from analyzer.protocol.ids import CONTROL_ID, FEEDBACK_ID, GPS_ID
from analyzer.protocol.types import (
    CRC_MISMATCH,
    LINK,
    TOPIC_COMMAND,
    CanFrame,
    Event,
    StreamChunk,
    diagnostic,
)
from analyzer.protocol.uav import encode_gps
from analyzer.tui.bridge import TuiBridge
from analyzer.tui.demo_traffic import FOREIGN_BASE_ID, session
from analyzer.tui.event_filter import EventFilter
from analyzer.tui.formatting import compass, describe_params, event_text, format_age, value_bar
from analyzer.tui.id_rows import frame_bits
from analyzer.tui.rates import RATE_WINDOW_S
from analyzer.tui.state import MonitorState

T0 = 1_700_000_000.0


def decoded(frames: list[CanFrame], wall: float | None = None) -> Batch:
    decoder = ProtocolDecoder()
    events = [e for f in frames for e in decoder.feed(f)]
    return Batch(list[RawItem](frames), events, wall if wall is not None else frames[-1].time)


def attitude_frames(t: float, **values: float) -> list[CanFrame]:
    message = encode_attitude(**values)  # type: ignore[arg-type]
    return [CanFrame(t + i * 0.001, FEEDBACK_ID, s) for i, s in enumerate(segments(message))]


def test_fold_shows_decoded_values() -> None:
    state = MonitorState()
    frames = [
        CanFrame(T0, CONTROL_ID, encode_command("gimbal_control", pan_speed_dps=-5.0)),
        CanFrame(T0 + 0.01, CONTROL_ID, encode_command("zoom", action="zoom_in")),
        CanFrame(T0 + 0.02, CONTROL_ID, encode_command("recording", action="start")),
        *attitude_frames(T0 + 0.1, pitch_deg=-12.5, yaw_deg=45.0, motor_yaw_deg=3.0),
        CanFrame(T0 + 0.2, GPS_ID, encode_gps(31.1234567, 118.1234567)),
        CanFrame(T0 + 0.3, 0x18FF0001, b"\x01\x02"),
    ]
    state.fold(decoded(frames))
    assert state.attitude is not None
    assert state.attitude.fields["pitch_deg"] == -12.5
    assert state.attitude.fields["yaw_deg"] == 45.0
    assert state.last_commands["zoom"].fields["action"] == "zoom_in"
    assert state.last_commands["recording"].fields["action"] == "start"
    assert state.last_commands["motion"].fields["pan_speed_dps"] == -5.0
    assert state.gps is not None and state.gps.fields["latitude_deg"] == pytest.approx(31.1234567)
    assert state.rows[CONTROL_ID].count == 3
    assert state.rows[FEEDBACK_ID].count == 4
    assert state.rows[0x18FF0001].label == "foreign"
    assert not state.rows[0x18FF0001].protocol
    assert [e.event.fields["name"] for e in state.command_log] == [
        "gimbal_control",
        "zoom",
        "recording",
    ]
    assert len(state.all_log) == 5  # + attitude + gps
    assert state.total.frames == len(frames)


def test_feedback_age_goes_stale_with_injected_time_only() -> None:
    state = MonitorState()
    state.fold(decoded(attitude_frames(T0, pitch_deg=0.0, yaw_deg=0.0), wall=T0 + 0.01))
    assert state.feedback_age == pytest.approx(0.003, abs=0.01)
    assert not state.feedback_stale
    state.advance(T0 + 0.6)
    assert not state.feedback_stale
    state.advance(T0 + 1.5)
    assert state.feedback_stale
    assert state.feedback_age == pytest.approx(1.497, abs=0.01)


def test_replay_time_axis_follows_the_frames_not_the_wall_clock() -> None:
    # a log recorded at t=100 s replayed now: ages are measured on the log's axis
    state = MonitorState()
    state.advance(T0 - 5.0)  # the screen ran on the wall clock before data came
    state.fold(decoded(attitude_frames(100.0, pitch_deg=1.0, yaw_deg=2.0), wall=T0))
    assert state.now == pytest.approx(100.003)
    state.advance(T0 + 0.5)
    assert state.feedback_age == pytest.approx(0.5, abs=0.01)
    state.advance(T0 + 2.0)
    assert state.feedback_stale


def test_rates_bus_load_and_sparkline_history() -> None:
    state = MonitorState()
    frames: list[RawItem] = [CanFrame(T0 + i / 100, 0x123, bytes(8)) for i in range(100)]
    frames.append(CanFrame(T0 + 1.0, 0x123, bytes(8)))  # closes the first second's sample
    state.fold(Batch(frames, [], T0 + 1.0))
    assert state.frames_per_s == pytest.approx(100.0)
    assert state.row_rate(state.rows[0x123]) == pytest.approx(100.0)
    assert state.bus_load == pytest.approx(100 * 131 / 1_000_000)
    assert state.frames_history[-1] == pytest.approx(100.0)
    # silence: rates fall, and are 0 once the silence is longer than the window
    state.advance(T0 + 3.0)
    assert 0 < state.frames_per_s < 50
    state.advance(T0 + 5.0)
    assert list(state.frames_history)[-3:] == [0.0, 0.0, 0.0]
    state.advance(T0 + 1.0 + RATE_WINDOW_S + 0.1)
    assert state.frames_per_s == 0.0 and state.bus_load == 0.0
    assert state.row_rate(state.rows[0x123]) == 0.0
    assert frame_bits(CanFrame(0, 1, bytes(8), extended=False)) == 111


def feedback_every(period: float, seconds: float, jitter: float = 0.02) -> list[CanFrame]:
    """Attitude feedback every ``period`` s (each message a little early or late)."""
    frames: list[CanFrame] = []
    for n in range(int(seconds / period)):
        late = jitter * ((n * 7919) % 11 - 5) / 5
        frames += attitude_frames(T0 + n * period + late, pitch_deg=1.0, yaw_deg=2.0)
    return frames


def test_the_feedback_rate_is_steady_while_feedback_comes() -> None:
    """The issue's case: sampled every 5 s, a 2 Hz feedback read 1.8, 1.0, 0.0, 0.9, 1.8 /s
    from one-second counts; from the messages' own times it reads 2.0 at any moment."""
    state = MonitorState()
    frames = feedback_every(0.5, 30.0)
    decoder = ProtocolDecoder()
    readings = []
    for start in range(0, len(frames), 4):  # a batch per message, as a capture makes them
        chunk = frames[start : start + 4]
        state.fold(
            Batch(list[RawItem](chunk), [e for f in chunk for e in decoder.feed(f)], chunk[-1].time)
        )
        for moment in (chunk[-1].time + 0.1, chunk[-1].time + 0.24, chunk[-1].time + 0.45):
            state.advance(moment)
            if moment > T0 + 5:
                readings.append(state.topic_rates["/gimbal/attitude"])
                row = state.rows[FEEDBACK_ID]
                assert state.row_rate(row) == pytest.approx(8.0, rel=0.1)
    assert min(readings) == pytest.approx(2.0, rel=0.1)
    assert max(readings) == pytest.approx(2.0, rel=0.1)


def test_a_slow_message_keeps_its_rate_between_two_and_stops_when_it_stops() -> None:
    state = MonitorState()
    frames = feedback_every(1.5, 12.0, jitter=0.0)
    state.fold(decoded(frames))
    for moment in (0.2, 0.7, 1.2, 1.4, 2.2):
        state.advance(frames[-1].time + moment)
        assert state.topic_rates["/gimbal/attitude"] == pytest.approx(1 / 1.5, rel=0.01)
    state.advance(frames[-1].time + 2.9)  # almost twice its interval: it has stopped
    assert 0 < state.topic_rates["/gimbal/attitude"] < 1 / 1.5
    state.advance(frames[-1].time + RATE_WINDOW_S + 0.1)
    assert state.topic_rates["/gimbal/attitude"] == 0.0


def test_counters_only_reset_on_request_and_totals_never() -> None:
    state = MonitorState()
    bad = diagnostic(T0, "can", CRC_MISMATCH, "feedback CRC", b"\x01")
    for i in range(3):
        state.fold(Batch([CanFrame(T0 + i, 0x10, b"\x00")], [bad], T0 + i))
    assert state.counters.kinds[CRC_MISMATCH] == 3
    state.clear_counters()
    assert state.counters.kinds[CRC_MISMATCH] == 0
    assert state.rows[0x10].count == 0
    assert state.total.kinds[CRC_MISMATCH] == 3
    assert state.total.frames == 3
    assert state.cleared_at is not None and state.clear_count == 1
    state.fold(Batch([CanFrame(T0 + 5, 0x10, b"\x00")], [bad], T0 + 5))
    assert state.counters.kinds[CRC_MISMATCH] == 1
    assert state.total.kinds[CRC_MISMATCH] == 4
    assert state.rows[0x10].count == 1


def test_logs_are_bounded_and_foreign_events_stay_out() -> None:
    state = MonitorState(log_limit=50)
    events = [
        Event(TOPIC_COMMAND, T0 + i, "can", {"name": "forward", "s_id": 15, "cmd": 2})
        for i in range(500)
    ]
    events.append(Event("/can/other", T0 + 600, "can", {"can_id": 5}))
    state.fold(Batch([], events, T0 + 600))
    assert len(state.command_log) == 50
    assert len(state.all_log) == 50
    assert state.command_log[-1].seq == 500
    assert state.total.events == 500


def test_changed_bytes_are_highlighted_for_a_second() -> None:
    state = MonitorState()
    state.fold(Batch([CanFrame(T0, 0x20, bytes([1, 2, 3, 4]))], [], T0))
    state.fold(Batch([CanFrame(T0 + 0.1, 0x20, bytes([1, 9, 3, 4]))], [], T0 + 0.1))
    row = state.rows[0x20]
    assert row.changed_mask(state.now) == (False, True, False, False)
    state.advance(T0 + 2.0)
    assert row.changed_mask(state.now) == (False, False, False, False)


def test_link_state_and_stream_rows() -> None:
    state = MonitorState()
    link = diagnostic(T0, "tcp", LINK, "connected to 127.0.0.1:2000", state="connected")
    chunk = StreamChunk(T0, b"\xeb\x90\x0a", source="tcp", direction="gs_to_idu")
    state.fold(Batch([chunk], [link], T0))
    assert state.link_state == "connected"
    assert state.counters.errors == 0  # link changes are not errors
    assert state.rows["tcp →idu"].count == 1
    assert state.total.chunks == 1


def test_demo_session_decodes_cleanly_into_the_state() -> None:
    state = MonitorState()
    frames = list(session(T0, 10.0, foreign_per_s=100, foreign_ids=4))
    state.fold(decoded(frames))
    assert state.counters.errors == 0
    assert state.feedback_count == 25  # 20 attitude + 5 ranging
    assert FOREIGN_BASE_ID + 3 in state.rows
    assert state.text is not None and state.text.fields["text"].startswith("waypoint")
    assert state.topic_rates["/uav/gps"] == pytest.approx(10.0)
    assert state.topic_rates["/gimbal/attitude"] == pytest.approx(2.0)


# -- filter ------------------------------------------------------------------------------------


def _cmd(name: str, **fields: object) -> Event:
    return Event(TOPIC_COMMAND, T0, "can", {"name": name, **fields})


def test_filter_terms() -> None:
    zoom = _cmd("zoom", action="zoom_in")
    pan = _cmd("gimbal_control", pan_speed_dps=1.0)
    crc = diagnostic(T0, "can", CRC_MISMATCH, "bad")
    gps = Event("/uav/gps", T0, "can", {"latitude_deg": 1.0})
    flt = EventFilter.parse("zoom")
    assert flt.matches_event(zoom, "zoom zoom_in")
    assert not flt.matches_event(pan, "gimbal_control pan")
    flt = EventFilter.parse("/gimbal -gimbal_control")
    assert flt.matches_event(zoom, "") and not flt.matches_event(pan, "")
    assert not flt.matches_event(gps, "")
    flt = EventFilter.parse("0xFF15")
    assert flt.matches_event(gps, "") and not flt.matches_event(zoom, "")
    assert flt.matches_row(0xFF15, "uav gps", "0x0000FF15")
    assert not flt.matches_row(0xF01, "control", "0x00000F01")
    flt = EventFilter.parse("crc")
    assert flt.matches_event(crc, "crc_mismatch: bad")
    assert EventFilter.parse("/uav").matches_row(1, "x", "y")  # topics do not hide rows
    assert not EventFilter.parse("  ").active


# -- bridge ------------------------------------------------------------------------------------


def test_bridge_coalesces_wakeups_and_hands_over_whole_batches() -> None:
    bridge = TuiBridge()
    wakes: list[int] = []
    bridge.handle(Batch(wall_time=1.0))  # before the app runs: kept
    bridge.connect(lambda: wakes.append(1))
    assert len(wakes) == 1
    for i in range(5):
        bridge.handle(Batch(wall_time=2.0 + i))
    assert len(wakes) == 1  # no new wake-up while one is pending
    batches, dropped = bridge.take()
    assert [b.wall_time for b in batches] == [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]
    assert dropped == 0
    bridge.handle(Batch(wall_time=7.0))
    assert len(wakes) == 2
    bridge.close()
    assert bridge.closed


def test_bridge_backlog_is_bounded_and_counted() -> None:
    bridge = TuiBridge(max_backlog=10)
    for i in range(25):
        bridge.handle(Batch(wall_time=float(i)))
    batches, dropped = bridge.take()
    assert len(batches) == 10 and dropped == 15
    assert batches[0].wall_time == 15.0


def test_bridge_from_another_thread_loses_nothing() -> None:
    n = 2000
    bridge = TuiBridge(max_backlog=n)
    wakes = threading.Semaphore(0)
    bridge.connect(wakes.release)

    def produce() -> None:
        for i in range(n):
            bridge.handle(Batch(wall_time=float(i)))

    thread = threading.Thread(target=produce)
    thread.start()
    got: list[float] = []
    while len(got) < n:
        assert wakes.acquire(timeout=5)
        batches, _ = bridge.take()
        got.extend(b.wall_time for b in batches)
    thread.join()
    assert got == [float(i) for i in range(n)]
    assert bridge.notifications <= n


# -- wording -----------------------------------------------------------------------------------


def test_wording() -> None:
    pan = Event(TOPIC_COMMAND, 0, "can", {"name": "gimbal_control", "pan_speed_dps": -5.0,
                                          "tilt_speed_dps": 0.0})  # fmt: skip
    assert describe_params(pan) == "pan -5.00 deg/s tilt 0.00 deg/s"
    assert event_text(pan) == "gimbal_control pan -5.00 deg/s tilt 0.00 deg/s"
    zoom = Event(TOPIC_COMMAND, 0, "can", {"name": "zoom", "action": "zoom_in", "raw": "0F 12"})
    assert "zoom" in event_text(zoom) and "zoom_in" in event_text(zoom)
    assert value_bar(0.0, -10, 10, 7) == "[--o--]"
    assert value_bar(None, -10, 10, 7) == "[--|--]"
    assert value_bar(10.0, -10, 10, 7) == "[--|-o]"
    assert compass(44) == "NE" and compass(359) == "N"
    assert format_age(None) == "never" and format_age(0.25) == "0.25 s"


def test_a_new_time_axis_restarts_the_rate_windows() -> None:
    state = MonitorState()
    first: list[RawItem] = [CanFrame(100.0 + i / 10, 0x1, b"\x00") for i in range(25)]
    state.fold(Batch(first, [], T0))
    second: list[RawItem] = [CanFrame(5.0 + i / 10, 0x1, b"\x00") for i in range(25)]
    state.fold(Batch(second, [], T0 + 3.0))
    assert state.now == pytest.approx(7.4)
    assert state.frames_per_s == pytest.approx(10.0)
    assert all(rate >= 0 for rate in state.frames_history)


def test_the_id_table_is_bounded() -> None:
    state = MonitorState(max_rows=10)
    frames: list[RawItem] = [CanFrame(T0 + i / 1000, 0x1000 + i, b"\x01") for i in range(100)]
    state.fold(Batch(frames, [], T0 + 0.1))
    assert len(state.rows) == 11
    assert state.rows["more IDs"].count == 90
    assert sum(row.count for row in state.rows.values()) == 100


def test_the_latest_response_finding_and_the_verdicts_so_far() -> None:
    from analyzer.pipeline import Batch
    from analyzer.protocol.types import Event
    from analyzer.tui.response_panel import render_response
    from analyzer.tui.state import MonitorState

    state = MonitorState()
    assert "commands are judged" in render_response(state, 60).plain
    finding = Event(
        "/analysis/response",
        10.0,
        "analysis",
        {
            "command": "look_down",
            "check": "target",
            "verdict": "not_obeyed",
            "detail": "pitch -90.0 not reached within 5 s: never moved (stayed at 0.0)",
        },
    )
    state.fold(Batch([], [finding]), 10.0)
    text = render_response(state, 60).plain
    assert "NOT OBEYED  look_down target" in text and "never moved" in text
    assert "1 not obeyed" in text and state.verdicts["not_obeyed"] == 1


def test_a_feedback_gap_is_lost_feedback_not_a_disobeyed_command() -> None:
    from analyzer.protocol.types import TOPIC_ANALYSIS_RESPONSE
    from analyzer.tui.response_panel import response_lines

    state = MonitorState()
    command = {"command": "look_down", "check": "target", "verdict": "obeyed", "detail": "ok"}
    gap = {
        "command": "feedback",
        "check": "feedback_gap",
        "verdict": "lost",
        "detail": "feedback lost: 1 message missing",
        "lost_messages": 1,
    }
    events = [
        Event(TOPIC_ANALYSIS_RESPONSE, T0, "analysis", command),
        Event(TOPIC_ANALYSIS_RESPONSE, T0 + 1, "analysis", gap),
    ]
    state.fold(Batch([], events))
    assert dict(state.verdicts) == {"obeyed": 1}  # as analyze counts: commands only
    assert (state.counts.gaps, state.counts.lost) == (1, 1)
    text = "\n".join(line.plain for line in response_lines(state, 100))
    assert "LOST" in text and "NOT OBEYED" not in text
    assert "1 obeyed" in text and "0 not obeyed" in text


def test_the_response_panel_shows_a_stick_movements_figures() -> None:
    from analyzer.protocol.types import TOPIC_ANALYSIS_RESPONSE
    from analyzer.tui.response_panel import response_lines

    state = MonitorState()
    movement = {
        "command": "gimbal_control",
        "check": "rate",
        "verdict": "partial",
        "detail": "pan turned 15.0 deg for 37.8 commanded (40 %), sluggish",
        "pan_ratio": 0.397,
        "lag_s": 0.3,
        "command_count": 49,
        "interval_mean_s": 0.05,
    }
    state.fold(Batch([], [Event(TOPIC_ANALYSIS_RESPONSE, T0, "analysis", movement)]))
    text = "\n".join(line.plain for line in response_lines(state, 100))
    assert "PARTIAL  gimbal_control rate" in text
    assert "pan x0.40  lag 0.30 s  49 commands  every 0.05 s" in text
    assert "sluggish" in text and "1 partial" in text
