"""Small things of the live monitor: the filter prompt, topic wording, log order, --tui."""

from __future__ import annotations

import asyncio

import pytest

from analyzer.pipeline import Batch
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.feedback import encode_attitude, segments
from analyzer.protocol.ids import FEEDBACK_ID, UAV_ATTITUDE_ID
from analyzer.protocol.types import CanFrame
from analyzer.protocol.uav import encode_uav_attitude
from analyzer.tui.command_log import CommandLog
from analyzer.tui.prompt_bar import PromptBar
from tests.test_tui_app import T0, Clock, batch_of, make_app, sample_frames, settle


@pytest.mark.slow
def test_the_filter_prompt_selects_the_old_text_so_typing_replaces_it() -> None:
    async def body() -> None:
        app, bridge = make_app(Clock(T0 + 0.5))
        async with app.run_test(size=(120, 40)) as pilot:
            bridge.handle(batch_of(sample_frames()))
            await settle(app, pilot)
            await pilot.press("f", *"zoom", "enter")
            assert app.filter.text == "zoom"
            await pilot.press("f")
            await pilot.pause()
            prompt = app.query_one(PromptBar)
            assert prompt.value == "zoom" and prompt.selected_text == "zoom"
            await pilot.press(*"focus", "enter")  # replaces, does not append
            assert app.filter.text == "focus"
            await pilot.press("f", "backspace", "enter")  # one key empties it: show all
            assert not app.filter.active

    asyncio.run(body())


@pytest.mark.slow
def test_the_all_topics_view_says_whose_attitude_it_is() -> None:
    async def body() -> None:
        clock = Clock(T0 + 0.5)
        app, bridge = make_app(clock)
        attitude = encode_attitude(pitch_deg=-37.25, yaw_deg=123.45, motor_yaw_deg=-12.5)
        frames = [
            CanFrame(T0 + i * 0.001, FEEDBACK_ID, s) for i, s in enumerate(segments(attitude))
        ]
        frames.append(CanFrame(T0 + 0.1, UAV_ATTITUDE_ID, encode_uav_attitude(1.5, -0.75, 149.9)))
        async with app.run_test(size=(120, 40)) as pilot:
            bridge.handle(batch_of(frames))
            await settle(app, pilot)
            await pilot.press("v")
            await settle(app, pilot)
            lines = app.query_one(CommandLog).visible_lines()
            assert any("gimbal attitude pitch -37.25 deg" in line for line in lines), lines
            assert any("uav attitude pitch 1.50 deg" in line for line in lines), lines

    asyncio.run(body())


def test_the_log_is_in_time_order_when_a_report_comes_late() -> None:
    """Two sources (or a proxy's two directions, read by two threads) can hand over an
    event after a later one of the other: the log shows them in time order all the same."""
    from analyzer.protocol.codec import encode_command
    from analyzer.protocol.ids import CONTROL_ID
    from analyzer.tui.state import MonitorState

    def command(t: float, name: str, channel: str = "can0") -> CanFrame:
        return CanFrame(T0 + t, CONTROL_ID, encode_command(name), channel=channel)

    decoder = ProtocolDecoder()
    newer = command(3.905, "look_down")
    older = command(3.449, "forward", "can1")
    state = MonitorState(log_limit=3)
    state.fold(Batch([newer], decoder.feed(newer), T0 + 4.0), T0 + 4.0)
    state.fold(Batch([older], decoder.feed(older), T0 + 4.1), T0 + 4.1)
    for log in (state.command_log, state.all_log):
        assert [e.event.time for e in log] == [T0 + 3.449, T0 + 3.905]
        assert [e.seq for e in log] == [2, 1]  # numbered as they came
    # a full log drops its oldest entry for the late one, as an append does
    for i in range(2):
        later = command(6 + i, "zoom_1x")
        state.fold(Batch([later], decoder.feed(later), T0 + 6 + i), T0 + 6 + i)
    late = command(6.5, "look_down", "can1")
    state.fold(Batch([late], decoder.feed(late), T0 + 9), T0 + 9)
    assert [e.event.time for e in state.command_log] == [T0 + 6, T0 + 6.5, T0 + 7]


@pytest.mark.slow
def test_the_cursor_stays_on_its_entry_when_an_older_one_is_inserted() -> None:
    from analyzer.protocol.codec import encode_command
    from analyzer.protocol.ids import CONTROL_ID

    async def body() -> None:
        clock = Clock(T0 + 0.5)
        app, bridge = make_app(clock)
        decoder = ProtocolDecoder()
        async with app.run_test(size=(120, 40)) as pilot:
            bridge.handle(batch_of(sample_frames(), decoder))
            await settle(app, pilot)
            await pilot.press("up")
            log = app.query_one(CommandLog)
            selected = log.selected
            assert selected is not None
            old = CanFrame(T0 - 1.0, CONTROL_ID, encode_command("forward"))
            bridge.handle(Batch([], decoder.feed(old), T0 + 0.6))
            await settle(app, pilot)
            assert log.selected is selected
            assert log.entries[0].event.fields.get("name") == "forward"

    asyncio.run(body())
