"""The monitor on a field laptop's 80x24 terminal: did it obey on a page of its own, a
stick's commands folded so diagnostics stay in view, cut lines that say so, and panels that
count what a TCP or UART source delivers."""

from __future__ import annotations

import asyncio
import contextlib
import re
from collections.abc import AsyncIterator

from textual.pilot import Pilot

from analyzer.analysis.findings import ResponseFinding
from analyzer.pipeline import Batch, RawItem
from analyzer.protocol.codec import encode_command
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.feedback import encode_attitude, segments
from analyzer.protocol.framing import wrap_control
from analyzer.protocol.ids import CONTROL_ID, FEEDBACK_ID
from analyzer.protocol.types import FROM_IDU, TO_IDU, CanFrame, Event, StreamChunk
from analyzer.sim.pilot import Stick
from analyzer.tui.app import MonitorApp
from analyzer.tui.bridge import TuiBridge
from analyzer.tui.command_log import CommandLog
from analyzer.tui.screen_text import screen_text
from tests.test_tui_layout import make_app, redraw, sample_batch

T0 = 1_717_400_000.0
SIZE = (80, 24)


def decoded(items: list[RawItem], events: list[Event] | None = None) -> Batch:
    decoder = ProtocolDecoder()
    out = [e for item in items for e in decoder.feed(item)]
    return Batch(items, sorted(out + (events or []), key=lambda e: e.time), items[-1].time)


def app_at(now: float) -> tuple[MonitorApp, TuiBridge]:
    bridge = TuiBridge(max_backlog=100_000)
    return MonitorApp(bridge, source_label="can:socketcan:can0", clock=lambda: now), bridge


@contextlib.asynccontextmanager
async def monitor(batch: Batch, now: float) -> AsyncIterator[tuple[MonitorApp, Pilot[int]]]:
    """The monitor on the laptop's terminal at the clock's ``now``, once it has drawn
    ``batch``."""
    app, bridge = app_at(now)
    async with app.run_test(size=SIZE) as pilot:
        bridge.handle(batch)
        await redraw(app, pilot)
        yield app, pilot


async def after_key(app: MonitorApp, pilot: Pilot[int], key: str) -> str:
    """The screen once ``key`` is pressed and the view redrawn."""
    await pilot.press(key)
    await redraw(app, pilot)
    return screen_text(app)


def finding(t: float, command: str, verdict: str, detail: str) -> Event:
    return ResponseFinding(command, t, "target", verdict, detail).to_event()


def test_a_number_key_shows_did_it_obey_with_the_findings_before_the_latest() -> None:
    findings = [
        finding(T0 + 1, "specified_angle", "obeyed", "pitch reached -45.0 in 0.8 s"),
        finding(T0 + 2, "look_down", "not_obeyed", "pitch stayed at -45.0 (never moved)"),
        finding(T0 + 3, "forward", "obeyed", "pitch reached 0.0 in 1.5 s; yaw reached 0.0"),
    ]
    frames: list[RawItem] = [CanFrame(T0 + 3.5, CONTROL_ID, encode_command("forward"))]

    async def body() -> None:
        async with monitor(decoded(frames, findings), T0 + 4) as (app, pilot):
            assert "5 Obey?" in screen_text(app).splitlines()[-1]
            assert "Did it obey?" not in screen_text(app)
            text = await after_key(app, pilot, "5")
            assert "─ Did it obey? ─" in text and "─ Gimbal ─" not in text
            assert "OBEYED  forward target" in text
            assert "1 not obeyed" in text and "2 obeyed" in text
            earlier = text[text.index("earlier") :]
            assert earlier.index("NOT OBEYED  look_down") < earlier.index("specified_angle")
            assert "pitch stayed at -45.0 (never moved)" in earlier
            assert "…" not in text

    asyncio.run(body())


def test_a_cut_log_line_ends_in_an_ellipsis_and_enter_shows_it_whole() -> None:
    batch = sample_batch()

    async def body() -> None:
        app, bridge = make_app(batch)
        async with app.run_test(size=SIZE) as pilot:
            bridge.handle(batch)
            await redraw(app, pilot)
            text = await after_key(app, pilot, "2")
            rows = [line for line in text.splitlines() if re.match(r"│\d\d:", line)]
            cut = [row for row in rows if "…" in row]
            assert cut and all(row.rstrip(" │").endswith("…") for row in cut)
            assert any("INCOMPLETE feedback message with only 3 of 4 segments" in r for r in cut)
            for _ in range(len(rows)):  # up the log to the INCOMPLETE line, then Enter
                await pilot.press("up")
                selected = app.query_one(CommandLog).selected
                if selected is not None and selected.event.fields.get("kind") == "incomplete":
                    break
            await pilot.press("enter")
            await pilot.pause()
            details = " ".join(screen_text(app).replace("█", " ").split())
            assert "Event details" in details
            assert "before the next header (segment lost?)" in details

    asyncio.run(body())


def stick_with_crc_errors(seconds: float) -> list[RawItem]:
    """A stick's gimbal_control every 50 ms and feedback every 0.5 s, one feedback message
    in five with a damaged CRC."""
    stick = Stick(pan_dps=20.0, seed=3)
    items: list[RawItem] = []
    for n in range(int(seconds * 20)):
        pan, tilt = stick.speeds(n / 20, seconds)
        data = encode_command("gimbal_control", pan_speed_dps=pan, tilt_speed_dps=tilt)
        items.append(CanFrame(T0 + n / 20, CONTROL_ID, data))
    for k in range(int(seconds * 2)):
        message = bytearray(encode_attitude(pitch_deg=1.0, yaw_deg=2.0))
        if k % 5 == 2:
            message[25] ^= 0xFF  # the first byte of its CRC
        for i, segment in enumerate(segments(bytes(message))):
            items.append(CanFrame(T0 + k / 2 + 0.01 + i * 0.001, FEEDBACK_ID, segment))
    return sorted(items, key=lambda item: item.time)


def test_a_stick_at_20_hz_is_one_log_line_and_the_crc_errors_stay_in_view() -> None:
    items = stick_with_crc_errors(8.0)

    async def body() -> None:
        async with monitor(decoded(items), items[-1].time + 0.1) as (app, pilot):
            text = await after_key(app, pilot, "2")
            assert text.count("CRC_MISMATCH") == 3  # every one of them, on one screen
            assert "gimbal_control x160 in 8.0 s, last pan" in text
            # all topics (v) show every command, as text mode's --all does
            assert (await after_key(app, pilot, "v")).count("gimbal_control pan") > 5
            await after_key(app, pilot, "v")
            log = app.query_one(CommandLog)
            run = next(e for e in log.entries if e.count > 1)
            app.show_detail(run)
            await pilot.pause()
            details = " ".join(screen_text(app).replace("█", " ").split())
            assert "repeated 160 times from" in details and "the last one below" in details

    asyncio.run(body())


def tcp_session(seconds: float) -> list[RawItem]:
    """The IDU's TCP stream: commands to it, feedback from it every 0.5 s."""
    items: list[RawItem] = []
    for k in range(int(seconds * 2)):
        t = T0 + k / 2
        command = wrap_control(encode_command("gimbal_control", pan_speed_dps=5.0))
        items.append(StreamChunk(t, command, source="tcp", direction=TO_IDU))
        feedback = encode_attitude(pitch_deg=1.0, yaw_deg=2.0)  # the 32 bytes as they are
        items.append(StreamChunk(t + 0.2, feedback, source="tcp", direction=FROM_IDU))
    return items


def test_a_tcp_source_s_panels_count_chunks_not_can_frames() -> None:
    items = tcp_session(10.0)

    async def body() -> None:
        async with monitor(decoded(items), items[-1].time + 0.1) as (app, pilot):
            assert "4 chunks/s" in screen_text(app)
            text = await after_key(app, pilot, "3")
            assert "Streams: chunks by direction" in text and "CAN IDs" not in text
            assert re.search(r"tcp ←idu\s+stream\s+20\s+2\.0", text), text
            text = await after_key(app, pilot, "4")
            assert "chunks/s 4" in text and "frames/s" not in text
            assert "40 chunks" in text and "0 frames" not in text

    asyncio.run(body())
