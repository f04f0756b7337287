"""The monitor app driven headless by Textual's pilot, with batches built from encoded frames."""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Coroutine
from typing import Any

import pytest
from rich.text import Text
from textual.pilot import Pilot

from analyzer.pipeline import Batch, RawItem
from analyzer.protocol.codec import encode_command
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.feedback import encode_attitude, segments
from analyzer.protocol.ids import CONTROL_ID, FEEDBACK_ID, GPS_ID
from analyzer.protocol.types import CanFrame
from analyzer.protocol.uav import encode_gps, encode_text
from analyzer.tui.app import MonitorApp
from analyzer.tui.bridge import TuiBridge
from analyzer.tui.command_log import CommandLog
from analyzer.tui.detail_screen import DetailScreen
from analyzer.tui.gimbal_panel import render_gimbal
from analyzer.tui.help_screen import HelpScreen
from analyzer.tui.id_table import IdTable
from analyzer.tui.screen_text import screen_text

T0 = 1_700_000_000.0
SIZE = (120, 40)


class Clock:
    """The app's injected clock: moves only when a test says so."""

    def __init__(self, now: float) -> None:
        self.now = now

    def __call__(self) -> float:
        return self.now


def sample_frames(t: float = T0) -> list[CanFrame]:
    frames = [
        CanFrame(t, CONTROL_ID, encode_command("gimbal_control", pan_speed_dps=-5.0)),
        CanFrame(t + 0.01, CONTROL_ID, encode_command("zoom", action="zoom_in")),
        CanFrame(t + 0.02, CONTROL_ID, encode_command("focus", action="auto_focus")),
        CanFrame(t + 0.03, CONTROL_ID, encode_command("recording", action="start")),
        CanFrame(t + 0.04, CONTROL_ID, encode_command("snapshot", mode="single")),
    ]
    attitude = encode_attitude(pitch_deg=-37.25, yaw_deg=123.45, motor_yaw_deg=-12.5)
    frames += [
        CanFrame(t + 0.1 + i * 0.001, FEEDBACK_ID, s) for i, s in enumerate(segments(attitude))
    ]
    frames.append(CanFrame(t + 0.2, GPS_ID, encode_gps(31.1234567, 118.1234567)))
    frames += [CanFrame(t + 0.3, cid, data) for cid, data in encode_text("hello gimbal")]
    frames.append(CanFrame(t + 0.4, 0x18FF0001, bytes([1, 2, 3, 4, 5, 6, 7, 8])))
    return frames


def batch_of(frames: list[CanFrame], decoder: ProtocolDecoder | None = None) -> Batch:
    decoder = decoder or ProtocolDecoder()
    events = [e for f in frames for e in decoder.feed(f)]
    return Batch(list[RawItem](frames), events, frames[-1].time + 0.01)


def make_app(clock: Clock, **kwargs: object) -> tuple[MonitorApp, TuiBridge]:
    bridge = TuiBridge()
    app = MonitorApp(
        bridge,
        source_label="file:sample.log",
        clock=clock,
        file_size=lambda path: 2_500_000,
        **kwargs,  # type: ignore[arg-type]
    )
    return app, bridge


async def settle(app: MonitorApp, pilot: Pilot[int]) -> None:
    """Let posted messages through, fold what waits and redraw now."""
    await pilot.pause()
    app.pull()
    app.refresh_view()
    await pilot.pause()


def run(test: Callable[[], Coroutine[Any, Any, None]]) -> None:
    asyncio.run(test())


def log_lines(app: MonitorApp) -> list[str]:
    return app.query_one(CommandLog).visible_lines()


def test_widgets_show_decoded_values_on_a_120x40_screen() -> None:
    async def body() -> None:
        clock = Clock(T0 + 0.5)
        app, bridge = make_app(clock, recording="flight.mcap")
        async with app.run_test(size=SIZE) as pilot:
            bridge.handle(batch_of(sample_frames()))
            await settle(app, pilot)
            text = screen_text(app)
            lines = text.splitlines()
            assert len(lines) == 40 and max(len(line) for line in lines) <= 120
            for expected in (
                "file:sample.log",
                "REC flight.mcap 2.5 MB",
                "-37.25°",
                "123.45°",
                "-12.50°",
                "locking",
                "tracking no",
                "zoom_in",
                "auto_focus",
                "single",
                "31.1234567° N",
                "118.1234567° E",
                "'hello gimbal'",
                "gimbal_control pan -5.00 deg/s",
                "0x00000F01",
                "0x030F0001",
                "0x18FF0001",
                "foreign",
                "crc_mismatch",
                "Quit",
                "Pause",
            ):
                assert expected in text, expected
            svg = app.export_screenshot()
            assert "123.45" in svg

    run(body)


@pytest.mark.slow
def test_feedback_age_turns_red_after_a_second_without_feedback() -> None:
    async def body() -> None:
        clock = Clock(T0 + 0.5)
        app, bridge = make_app(clock)
        async with app.run_test(size=SIZE) as pilot:
            bridge.handle(batch_of(sample_frames()))
            await settle(app, pilot)
            assert not app.state.feedback_stale
            assert app.state.feedback_age == pytest.approx(0.387, abs=0.002)
            assert "feedback 0.39 s ago" in screen_text(app)
            clock.now = T0 + 2.0
            await settle(app, pilot)
            assert app.state.feedback_stale
            assert "feedback 1.89 s ago" in screen_text(app)
            text = render_gimbal(app.state)
            styles = [str(s.style) for s in text.spans if "ago" in text.plain[s.start : s.end]]
            assert any("red" in style for style in styles)

    run(body)


@pytest.mark.slow
def test_pause_keeps_counting_and_resume_catches_up() -> None:
    async def body() -> None:
        clock = Clock(T0 + 0.5)
        app, bridge = make_app(clock)
        decoder = ProtocolDecoder()
        async with app.run_test(size=SIZE) as pilot:
            bridge.handle(batch_of(sample_frames(), decoder))
            await settle(app, pilot)
            await pilot.press("p")
            assert app.paused
            frame = CanFrame(T0 + 1.0, CONTROL_ID, encode_command("look_down"))
            bridge.handle(batch_of([frame], decoder))
            clock.now = T0 + 1.1
            await settle(app, pilot)
            assert not any("look_down" in line for line in log_lines(app))
            assert app.state.last_commands["motion"].fields["name"] == "look_down"  # still folded
            assert "PAUSED +1" in screen_text(app)
            await pilot.press("p")
            await settle(app, pilot)
            assert not app.paused
            assert any("look_down" in line for line in log_lines(app))
            assert "PAUSED" not in screen_text(app)

    run(body)


@pytest.mark.slow
def test_filter_search_raw_view_and_clear() -> None:
    async def body() -> None:
        clock = Clock(T0 + 0.5)
        app, bridge = make_app(clock)
        async with app.run_test(size=SIZE) as pilot:
            bridge.handle(batch_of(sample_frames()))
            await settle(app, pilot)
            await pilot.press("f", *"zoom", "enter")
            await settle(app, pilot)
            lines = log_lines(app)
            assert lines and all("zoom" in line for line in lines)
            assert "filter zoom" in screen_text(app)
            app.set_filter("0xFF15")
            await settle(app, pilot)
            text = screen_text(app)
            assert "0x0000FF15" in text and "0x00000F01" not in text  # ID table filtered too
            await pilot.press("f", "ctrl+u", "enter")  # empty: show all
            assert not app.filter.active
            await pilot.press("v")  # every decoded topic
            await settle(app, pilot)
            assert any("attitude pitch -37.25 deg" in line for line in log_lines(app))
            await pilot.press("v")
            await pilot.press("r")
            await settle(app, pilot)
            assert any("0F 12 01 00 00 00 00 00" in line for line in log_lines(app))
            await pilot.press("slash", *"rec", "enter")
            await settle(app, pilot)
            selected = app.query_one(CommandLog).selected
            assert selected is not None and selected.event.fields["name"] == "recording"
            assert app.state.counters.frames == len(sample_frames())
            await pilot.press("c")
            await settle(app, pilot)
            assert app.state.counters.frames == 0
            assert app.state.rows[CONTROL_ID].count == 0
            assert app.state.total.frames == len(sample_frames())
            assert "cleared 1x" in screen_text(app)

    run(body)


@pytest.mark.slow
def test_select_event_shows_fields_and_raw_bytes_and_help_opens() -> None:
    async def body() -> None:
        clock = Clock(T0 + 0.5)
        app, bridge = make_app(clock)
        async with app.run_test(size=SIZE) as pilot:
            bridge.handle(batch_of(sample_frames()))
            await settle(app, pilot)
            await pilot.press("home", "enter")  # the oldest entry: gimbal_control
            await pilot.pause()
            assert isinstance(app.screen, DetailScreen)
            text = screen_text(app)
            assert "pan_speed_dps" in text and "-5.0" in text
            assert "0F 04 0C FE 00 00 00 00" in text
            await pilot.press("escape")
            await pilot.pause()
            assert not isinstance(app.screen, DetailScreen)
            await pilot.press("question_mark")
            await pilot.pause()
            assert isinstance(app.screen, HelpScreen)
            assert "clear counters" in screen_text(app)
            await pilot.press("escape")
            await pilot.pause()
            assert not isinstance(app.screen, HelpScreen)

    run(body)


def test_end_of_source_is_shown_and_backlog_drops_are_counted() -> None:
    async def body() -> None:
        clock = Clock(T0 + 0.5)
        app, bridge = make_app(clock)
        bridge.max_backlog = 2
        async with app.run_test(size=SIZE) as pilot:
            app.bridge.disconnect()  # as if the UI stalled: nothing is taken
            for i in range(5):
                bridge.handle(Batch([CanFrame(T0 + i, 0x55, b"\x01")], [], T0 + i))
            bridge.close()
            await settle(app, pilot)
            text = screen_text(app)
            assert "source ended" in text
            assert "display skipped 3 batches" in text

    run(body)


def test_id_table_rows_are_keyed_and_updated_in_place() -> None:
    async def body() -> None:
        clock = Clock(T0 + 0.5)
        app, bridge = make_app(clock)
        async with app.run_test(size=SIZE) as pilot:
            decoder = ProtocolDecoder()
            bridge.handle(batch_of(sample_frames(), decoder))
            await settle(app, pilot)
            table = app.query_one(IdTable)
            rows_before = table.row_count
            updates_before = table.updates
            later = [CanFrame(T0 + 0.45, 0x18FF0001, bytes([1, 2, 3, 4, 5, 6, 7, 9]))]
            bridge.handle(batch_of(later, decoder))
            await settle(app, pilot)
            assert table.row_count == rows_before  # same key, same row
            assert table.updates > updates_before
            cells = [str(c) for c in table.get_row("0x18FF0001")]
            assert cells[2].strip() == "2"
            assert cells[4] == "01 02 03 04 05 06 07 09"
            data = table.get_cell("0x18FF0001", "data")
            assert isinstance(data, Text)
            changed = [data.plain[s.start : s.end] for s in data.spans if s.style]
            assert changed == ["09"]  # only the byte that changed is highlighted

    run(body)
