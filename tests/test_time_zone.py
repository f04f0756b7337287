"""The time zone is a value handed to what shows times to people, not a switch of the
process: UTC by default, local time with --local-time, each output in its own zone. Texts
that become data (a diagnostic's detail, a check's verdict, JSON) are UTC whatever the
display shows (docs/explanation/time-bases.md)."""

from __future__ import annotations

import asyncio
import dataclasses
import inspect
import json
import types
from pathlib import Path

import pytest

from analyzer import timefmt
from analyzer.pipeline import Batch, RawItem
from analyzer.protocol.codec import encode_command
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.feedback import encode_attitude, segments
from analyzer.protocol.ids import CONTROL_ID, FEEDBACK_ID
from analyzer.protocol.types import LINK, CanFrame, Event, diagnostic
from analyzer.render import render_event
from analyzer.timefmt import LOCAL, UTC, TimeZone
from tests.fleet_flights import cli_output as cli

T = 1_715_680_801.253  # 2024-05-14 10:00:01.253Z; 15:30:01.253+05:30 in India
SAMPLE = str(Path(__file__).resolve().parents[1] / "samples" / "flight-candump.log")


def flight_events(t: float = T) -> list[Event]:
    """A command and the attitude feedback after it."""
    frames = [CanFrame(t, CONTROL_ID, encode_command("gimbal_control", pan_speed_dps=-5.0))]
    attitude = encode_attitude(pitch_deg=-10.0, yaw_deg=20.0, motor_yaw_deg=5.0)
    frames += [
        CanFrame(t + 0.5 + i * 0.001, FEEDBACK_ID, s) for i, s in enumerate(segments(attitude))
    ]
    decoder = ProtocolDecoder()
    return [e for f in frames for e in decoder.feed(f)] + decoder.close()


def test_timefmt_has_no_switch_and_no_mutable_state() -> None:
    assert not hasattr(timefmt, "use_local_time")
    assert not hasattr(timefmt, "local_time")
    assert "global " not in inspect.getsource(timefmt)
    for name, value in vars(timefmt).items():
        if name.startswith("__") or callable(value) or isinstance(value, types.ModuleType):
            continue
        if type(value).__module__ in ("typing", "__future__"):
            continue  # Final, the annotations future
        assert isinstance(value, (bool, int, float, str, TimeZone)), f"{name}: mutable state"
    with pytest.raises(dataclasses.FrozenInstanceError):
        UTC.local = True  # type: ignore[misc]
    assert timefmt.chosen_zone(True) is LOCAL and timefmt.chosen_zone(False) is UTC
    assert TimeZone() == UTC  # UTC unless asked otherwise


def test_each_zone_formats_its_own_way(india_time: None) -> None:
    assert UTC.format_clock(T) == "10:00:01.253Z"
    assert LOCAL.format_clock(T) == "15:30:01.253+05:30"
    assert UTC.format_datetime(T) == "2024-05-14 10:00:01.253Z"
    assert LOCAL.format_datetime(T) == "2024-05-14 15:30:01.253+05:30"
    assert len(UTC.format_clock(T)) == UTC.clock_width
    assert len(LOCAL.format_clock(T)) == LOCAL.clock_width
    assert LOCAL.format_clock(12.3456) == UTC.format_clock(12.3456) == "12.346"


def test_a_local_report_and_utc_lines_made_in_one_process(india_time: None) -> None:
    """One process, two outputs, two zones: neither changes the other (a process-wide
    switch could not do this: the report would set it for the lines too)."""
    from analyzer.report.collect import ReportData
    from analyzer.report.page import render

    events = flight_events()
    data = ReportData(source="bench", format_name="candump")
    for event in events:
        data.add(event)
    local_page = render(data, "tolerance 1 deg", zone=LOCAL)
    line = render_event(events[0])
    utc_page = render(data, "tolerance 1 deg")
    assert line.startswith("10:00:01.253Z ")
    assert "2024-05-14 15:30:01.253+05:30" in local_page
    assert "Times in the tables are local time" in local_page
    assert "2024-05-14 10:00:01.253Z" in utc_page and "Times are UTC." in utc_page
    assert "+05:30" not in utc_page
    assert render_event(events[0], zone=LOCAL).startswith("15:30:01.253+05:30 ")


def test_the_monitor_in_local_time_beside_utc_lines(india_time: None) -> None:
    from analyzer.tui.app import MonitorApp
    from analyzer.tui.bridge import TuiBridge
    from analyzer.tui.command_log import CommandLog
    from analyzer.tui.detail_screen import render_detail

    events = flight_events()
    frames = [CanFrame(T, CONTROL_ID, encode_command("gimbal_control", pan_speed_dps=-5.0))]

    async def body() -> None:
        bridge = TuiBridge()
        app = MonitorApp(bridge, source_label="file:x.log", clock=lambda: T + 1, zone=LOCAL)
        async with app.run_test(size=(120, 40)) as pilot:
            bridge.handle(Batch(list[RawItem](frames), events, T + 1))
            await pilot.pause()
            app.pull()
            app.refresh_view()
            await pilot.pause()
            shown = app.query_one(CommandLog).visible_lines()
            assert any(line.startswith("15:30:01.253+05:30") for line in shown), shown
            # meanwhile, in the same process, a text line keeps UTC
            assert render_event(events[0]).startswith("10:00:01.253Z ")

    asyncio.run(body())
    detail = render_detail(events[0], zone=LOCAL)
    cells = [str(cell) for column in detail.columns for cell in column.cells]
    assert any("15:30:01.253+05:30" in cell for cell in cells)


def test_the_status_words_take_the_zone_they_are_given(india_time: None) -> None:
    """The monitor's status bar and record's status line: the link and the bus."""
    from analyzer.bus_hints import bus_hints
    from analyzer.link_status import LinkStatus
    from analyzer.tui.state import MonitorState
    from analyzer.tui.status_bar import StatusInfo, render_status

    link = LinkStatus()
    link.fold([diagnostic(T, "can0", LINK, "connection lost", state="lost")])
    assert "since 15:30:01.253+05:30" in link.describe(T + 2, LOCAL)
    assert "since 10:00:01.253Z" in link.describe(T + 2)
    bus_off = CanFrame(T, 0x040, bytes(8), True, "can0", is_error=True)
    state = MonitorState()
    state.fold(Batch([bus_off], ProtocolDecoder().feed(bus_off)), wall_time=T + 0.5)
    local = render_status(state, StatusInfo(source="can:socketcan:can0", zone=LOCAL)).plain
    utc = render_status(state, StatusInfo(source="can:socketcan:can0")).plain
    assert "worst bus-off 15:30:01.253+05:30" in local
    assert "worst bus-off 10:00:01.253Z" in utc
    hints = " ".join(bus_hints(state.bus, 1, LOCAL))
    assert "went bus-off at 2024-05-14 15:30:01.253+05:30" in hints


def test_the_command_line_zone_lasts_one_command(india_time: None) -> None:
    local = cli("--local-time", "decode", SAMPLE)
    utc = cli("decode", SAMPLE)  # the same process: nothing left over from the first
    after = cli("decode", SAMPLE, "--local-time")  # also after the command name
    assert local.splitlines()[0].startswith("15:30:00.010+05:30 ")
    assert utc.splitlines()[0].startswith("10:00:00.010Z ")
    assert after == local
    summary = cli("--local-time", "decode", SAMPLE, "--summary")
    assert "2024-05-14 15:30:00.010+05:30 .. 2024-05-14 15:30:19.850+05:30" in summary
    report = cli("--local-time", "analyze", SAMPLE)
    assert "times are local, 2024-05-14" in report
    assert "\n15:30:02.004+05:30  gimbal_control" in report
    assert "times are UTC, 2024-05-14" in cli("analyze", SAMPLE)


def test_a_recordings_times_in_info_follow_the_flag(india_time: None, tmp_path: Path) -> None:
    recording = tmp_path / "flight.mcap"
    cli("convert", SAMPLE, "-o", str(recording), "-q")
    assert "time range  2024-05-14 15:30:00.010+05:30 .. " in cli(
        "--local-time", "info", str(recording)
    )
    assert "time range  2024-05-14 10:00:00.010Z .. " in cli("info", str(recording))


def test_a_diagnostics_words_are_utc_whatever_is_shown(india_time: None, tmp_path: Path) -> None:
    """A damaged timestamp's diagnostic is data (it goes into recordings and JSON): its
    sentence is UTC with --local-time too; the line's own time column follows the flag."""
    lines = Path(SAMPLE).read_text(encoding="utf-8").splitlines(keepends=True)[:40]
    lines[10] = "(0715680800" + lines[10][11:]  # a flipped digit: 1992
    log = tmp_path / "flight.log"
    log.write_text("".join(lines), encoding="utf-8")
    found = [
        json.loads(line) for line in cli("--local-time", "decode", str(log), "--json").splitlines()
    ]
    (bad,) = [e for e in found if e.get("kind") == "bad_frame"]
    assert "before the capture (10:00:00." in bad["detail"] and "+05:30" not in bad["detail"]
    (text,) = [
        line for line in cli("--local-time", "decode", str(log)).splitlines() if "BAD_FRAME" in line
    ]
    assert text.startswith("15:30:00.") and "before the capture (10:00:00." in text
    recording = tmp_path / "flight.mcap"
    cli("--local-time", "convert", str(log), "-o", str(recording), "-q")
    stored = [
        json.loads(line)
        for line in cli("decode", str(recording), "--json", "--stored").splitlines()
        if "bad_frame" in line
    ]
    assert stored and stored[0]["detail"] == bad["detail"]


def test_a_checks_verdict_sentence_is_utc() -> None:
    """A check's verdicts are written into its recording and its JSON: always UTC."""
    from analyzer.check.judge import Evidence, Measured, undecided
    from analyzer.check.steps import Attitude, Plan

    evidence = Evidence(
        plan=Plan((), Attitude()),
        started_at=T,
        ended_at=T + 5.0,
        judged=[],
        samples=[],
        feedback_times=[T],
        damaged=0,
        findings={},
    )
    why = undecided(evidence, Measured(unmeasured=["no attitude feedback"]), [])
    assert "(from 10:00:01.253Z)" in why
