"""The monitor at the terminal sizes field engineers use: every value readable, none cut off.

The sample flight log is replayed into the app headless at 80x24, 100x30, 120x40 and
160x45. Each value a field engineer needs must appear in full, on one line, on the main
screen or on the page one number key away; only a log line too long for its panel is cut,
and it ends in an ellipsis (Enter shows it whole).
"""

from __future__ import annotations

import asyncio
import re
from collections import Counter
from pathlib import Path

import pytest
from textual.pilot import Pilot

from analyzer.inputs import open_input
from analyzer.pipeline import Batch, RawItem
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.types import (
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_UAV_ALTITUDE,
    TOPIC_UAV_ATTITUDE,
    TOPIC_UAV_GPS,
    TOPIC_UAV_TEXT,
    CanFrame,
    Event,
)
from analyzer.tui.app import PAGES, MonitorApp
from analyzer.tui.bridge import TuiBridge
from analyzer.tui.command_log import CommandLog
from analyzer.tui.formatting import labelled
from analyzer.tui.screen_text import screen_text

pytestmark = pytest.mark.slow  # the monitor UI at several sizes, seconds each

SAMPLE = Path(__file__).resolve().parent.parent / "samples" / "flight-candump.log"
SIZES = [(80, 24), (100, 30), (120, 40), (160, 45)]
SOURCE = "file:samples/flight-candump.log"
LOG_ROW = re.compile(r"^[│|]?\d\d:\d\d:\d\d\.\d{3}")
CUT = re.compile(r"…[^│]{0,2}│")  # the ellipsis, the scrollbar's gutter, the log's border
RECORDING = "flight.mcap"


def sample_batch() -> Batch:
    """The whole sample flight, decoded, as one batch (as the capture would deliver it)."""
    decoder = ProtocolDecoder()
    items: list[RawItem] = []
    events: list[Event] = []
    for item in open_input(str(SAMPLE)):
        if isinstance(item, Event):
            events.append(item)
            continue
        items.append(item)
        events.extend(decoder.feed(item))
    return Batch(items, events, items[-1].time)


def last(events: list[Event], topic: str) -> Event:
    return [e for e in events if e.topic == topic][-1]


def expected_values(batch: Batch) -> dict[str, str]:
    """What a field engineer must be able to read, worded as the screen words it."""
    events = batch.events
    att = last(events, TOPIC_GIMBAL_ATTITUDE).fields
    gps = last(events, TOPIC_UAV_GPS).fields
    alt = last(events, TOPIC_UAV_ALTITUDE).fields
    uav = last(events, TOPIC_UAV_ATTITUDE).fields
    text = last(events, TOPIC_UAV_TEXT).fields
    kinds = Counter(e.fields["kind"] for e in events if e.topic == TOPIC_DIAGNOSTICS)
    lat, lon = float(gps["latitude_deg"]), float(gps["longitude_deg"])
    values = {
        "gimbal pitch": f"{att['pitch_deg']:.2f}°",
        "gimbal yaw": f"{att['yaw_deg']:.2f}°",
        "gimbal motor yaw": f"motor yaw {att['motor_yaw_deg']:8.2f}°",
        "feedback age": "feedback 0.40 s ago",  # last feedback 0.4 s before the clock
        "feedback rate": "2.0/s",  # the gimbal answers every 500 ms
        "mode": f"mode {labelled(att, 'control_mode')[0]}",
        "tracking": "tracking no",
        "UAV latitude": f"{abs(lat):.7f}° {'N' if lat >= 0 else 'S'}",
        "UAV longitude": f"{abs(lon):.7f}° {'E' if lon >= 0 else 'W'}",
        "UAV altitude": f"{float(alt['altitude_m']):.2f} m",
        "UAV attitude": (
            f"pitch {uav['pitch_deg']:.2f} roll {uav['roll_deg']:.2f} yaw {uav['yaw_deg']:.2f}°"
        ),
        "UAV text": repr(text["text"]),
        "source": SOURCE,
        "recording": f"REC {RECORDING} 123.5 kB",
        "link state": "receiving",
        "frames total": f"{len(batch.items):,} frames",
        "errors total": f"{sum(kinds.values()):,} errors",
    }
    for kind, n in kinds.items():
        values[f"counter {kind}"] = f"{kind} {n}"
    values["counter bus_error"] = "bus_error 0"
    # the latest command of each kind, as the gimbal panel words it
    commands = [e for e in events if e.topic == TOPIC_COMMAND]
    assert commands[-1].fields["name"] == "quick_calibration"
    values.update(
        {
            "last zoom": "zoom  zoom_1x",
            "last focus": "focus x 2000 y 3000 width 400 height 400",
            "last recording": "rec   stop",
            "last snapshot": "snap  continuous shots 3",
            "last move": "move  forward",
        }
    )
    return values


def make_app(batch: Batch) -> tuple[MonitorApp, TuiBridge]:
    now = batch.items[-1].time + 0.3
    bridge = TuiBridge()
    app = MonitorApp(
        bridge,
        source_label=SOURCE,
        recording=RECORDING,
        clock=lambda: now,
        file_size=lambda path: 123_456,
    )
    return app, bridge


async def redraw(app: MonitorApp, pilot: Pilot[int]) -> None:
    await pilot.pause()
    app.pull()
    app.refresh_view()
    await pilot.pause()


async def screens(app: MonitorApp, pilot: Pilot[int]) -> dict[str, str]:
    """The main screen, and each page one number key away (when the screen is paged)."""
    shown = {"main": screen_text(app)}
    if app.paged:
        for key in PAGES:
            await pilot.press(key)
            await redraw(app, pilot)
            shown[f"key {key}"] = screen_text(app)
        await pilot.press("1")
        await redraw(app, pilot)
    return shown


def missing_values(values: dict[str, str], shown: dict[str, str]) -> list[str]:
    lines = [line for text in shown.values() for line in text.splitlines()]
    return [name for name, value in values.items() if not any(value in line for line in lines)]


@pytest.mark.parametrize(("width", "height"), SIZES, ids=[f"{w}x{h}" for w, h in SIZES])
def test_every_value_is_readable_in_full(width: int, height: int) -> None:
    batch = sample_batch()
    values = expected_values(batch)

    async def body() -> None:
        app, bridge = make_app(batch)
        async with app.run_test(size=(width, height)) as pilot:
            bridge.handle(batch)
            await redraw(app, pilot)
            shown = await screens(app, pilot)
            for name, text in shown.items():
                lines = text.splitlines()
                assert len(lines) == height and max(map(len, lines)) <= width, name
                # only a log line is cut (ending in … at its border; Enter shows it whole)
                cut = [line for line in lines if "…" in line]
                assert all(LOG_ROW.match(line) and CUT.search(line) for line in cut), text
            assert missing_values(values, shown) == [], "\n\n".join(shown.values())
            if app.paged:
                # the footer names the page keys; everything else is still on ? help
                footer = shown["main"].splitlines()[-1]
                for key, (_, label) in PAGES.items():
                    assert f"{key} {label}" in footer
                for name, text in shown.items():  # every page's footer, whatever has focus
                    assert text.splitlines()[-1].rstrip().endswith("? Help"), name
            else:
                # wide terminals keep the all-in-one screen: every value without a key press
                assert missing_values(values, {"main": shown["main"]}) == []
                assert "CAN IDs" in shown["main"] and "Diagnostics" in shown["main"]

    asyncio.run(body())


def test_80x24_is_paged_and_120x40_is_all_in_one() -> None:
    batch = sample_batch()

    async def body() -> None:
        for size, paged in (((80, 24), True), ((100, 30), True), ((120, 40), False)):
            app, bridge = make_app(batch)
            async with app.run_test(size=size) as pilot:
                bridge.handle(batch)
                await redraw(app, pilot)
                assert app.paged is paged
                text = screen_text(app)
                assert ("Diagnostics" in text) is not paged
                if paged:
                    await pilot.press("3")
                    await redraw(app, pilot)
                    text = screen_text(app)
                    assert "0x030F0001 feedback" in text and "─ Gimbal ─" not in text

    asyncio.run(body())


def test_resizing_re_lays_out_and_keeps_the_state() -> None:
    batch = sample_batch()
    values = expected_values(batch)

    async def body() -> None:
        app, bridge = make_app(batch)
        async with app.run_test(size=(160, 45)) as pilot:
            bridge.handle(batch)
            await redraw(app, pilot)
            await pilot.press("c")  # counters cleared: must survive the resizes
            await pilot.press("up", "up")  # a cursor in the log: must survive too
            await redraw(app, pilot)
            log = app.query_one(CommandLog)
            cursor = log.cursor_seq
            assert cursor is not None and not app.paged
            await pilot.resize_terminal(80, 24)
            await redraw(app, pilot)
            assert app.paged and app.size == (80, 24)
            text = screen_text(app)
            assert len(text.splitlines()) == 24 and "…" not in text
            assert "1 Gimbal" in text.splitlines()[-1]
            await pilot.press("2")
            await redraw(app, pilot)
            assert log.cursor_seq == cursor
            assert "Log: commands + diagnostics" in screen_text(app)
            await pilot.press("4")
            await redraw(app, pilot)
            assert "cleared 1x" in screen_text(app)
            later = CanFrame(batch.items[-1].time + 0.1, 0x18FF0001, b"\x01")
            bridge.handle(Batch([later], [], later.time))
            await redraw(app, pilot)
            await pilot.resize_terminal(160, 45)
            await redraw(app, pilot)
            assert not app.paged
            text = screen_text(app)
            # everything but the counters the user cleared (to 0) and the one more frame
            missing = missing_values(values, {"main": text})
            assert "frames total" in missing
            missing.remove("frames total")
            assert missing and all(name.startswith("counter ") for name in missing)
            assert "crc_mismatch 0" in text and "cleared 1x" in text
            assert "0x18FF0001" in text  # the frame that came while small is shown
            assert f"{len(batch.items) + 1:,} frames" in text
            assert log.cursor_seq == cursor
            assert "5 Obey?" not in text  # no page keys when everything is on screen

    asyncio.run(body())


def test_help_and_details_fit_an_80x24_terminal() -> None:
    batch = sample_batch()

    async def body() -> None:
        app, bridge = make_app(batch)
        async with app.run_test(size=(80, 24)) as pilot:
            bridge.handle(batch)
            await redraw(app, pilot)
            await pilot.press("question_mark")
            await pilot.pause()
            text = screen_text(app)
            lines = text.splitlines()
            assert all(line.startswith("█") and line.endswith("█") for line in lines), text
            assert "1 2 3 4" in text and "quit: stop the capture, finalise the" in text
            await pilot.press("escape", "2", "enter")
            await pilot.pause()
            text = screen_text(app)
            assert "Event details" in text and "kind        bad_line" in text
            assert all(line.endswith("█") for line in text.splitlines()), text

    asyncio.run(body())
