"""The monitor on a real Capture: batches through the bridge, quitting stops it and closes sinks."""

from __future__ import annotations

import argparse
import asyncio
import importlib
import time
from pathlib import Path
from typing import Any

import pytest
from textual.app import App
from textual.pilot import Pilot

from analyzer.capture import Capture
from analyzer.cli import build_parser
from analyzer.commands import monitor
from analyzer.errors import UsageError
from analyzer.pipeline import Batch
from analyzer.protocol.types import CanFrame
from analyzer.tui.app import MonitorApp, add_sink, run_app
from analyzer.tui.bridge import TuiBridge
from analyzer.tui.demo_traffic import session
from analyzer.tui.screen_text import screen_text

T0 = 1_700_000_000.0


class ListSource:
    """Hands out its frames, then stays quiet like a live bus (or ends, with ``finite``)."""

    description = "test:list"
    source_name = "test"

    def __init__(self, frames: list[CanFrame], *, finite: bool = False) -> None:
        self.frames = list(frames)
        self.finite = finite
        self.closed = False

    def read(self, timeout: float) -> list[CanFrame]:
        if self.frames:
            out, self.frames = self.frames[:500], self.frames[500:]
            return out
        if self.finite:
            raise EOFError
        time.sleep(min(timeout, 0.01))
        return []

    def close(self) -> None:
        self.closed = True


class RecordingSink:
    """Stands in for the MCAP writer: counts what it got and whether it was closed."""

    def __init__(self) -> None:
        self.frames = 0
        self.closed = False

    def handle(self, batch: Batch) -> None:
        self.frames += len(batch.items)

    def close(self) -> None:
        self.closed = True


async def wait_for(pilot: Pilot[int], condition: object, timeout: float = 10.0) -> None:
    deadline = time.monotonic() + timeout
    while not condition():  # type: ignore[operator]
        assert time.monotonic() < deadline, "timed out"
        await pilot.pause(0.02)


def test_quit_stops_the_capture_and_finalises_the_sinks() -> None:
    frames = list(session(T0, 3.0, foreign_per_s=200))
    source = ListSource(frames)
    sink = RecordingSink()
    capture = Capture(source, [sink], batch_interval=0.02)
    bridge = TuiBridge()
    add_sink(capture, bridge)
    app = MonitorApp(bridge, capture=capture, source_label=source.description)

    async def body() -> None:
        capture.start()
        async with app.run_test(size=(120, 40)) as pilot:
            await wait_for(pilot, lambda: app.state.total.frames == len(frames))
            app.refresh_view()
            await pilot.pause()
            text = screen_text(app)
            assert "test:list" in text and "0x18FF5000" in text
            assert app.state.attitude is not None
            assert capture.running
            await pilot.press("q")
            await wait_for(pilot, lambda: not capture.running)
        assert app.return_code == 0

    asyncio.run(body())
    assert sink.closed and bridge.closed and source.closed
    assert sink.frames == len(frames)
    assert capture.stop_reason == "stopped"


@pytest.mark.slow
def test_a_finite_source_ends_and_the_screen_says_so() -> None:
    frames = list(session(T0, 2.0))
    capture = Capture(ListSource(frames, finite=True), [], batch_interval=0.02)
    bridge = TuiBridge()
    add_sink(capture, bridge)
    app = MonitorApp(bridge, capture=capture, source_label="test:list")

    async def body() -> None:
        capture.start()
        async with app.run_test(size=(120, 40)) as pilot:
            await wait_for(pilot, lambda: app.state.source_ended)
            app.refresh_view()
            await pilot.pause()
            assert "source ended" in screen_text(app)
            assert app.state.total.frames == len(frames)
            await pilot.press("q")

    asyncio.run(body())
    assert capture.stop_reason == "end of input"


def _file_inputs_available() -> bool:
    try:
        module = importlib.import_module("analyzer.inputs")
    except ImportError:
        return False
    return hasattr(module, "open_input")


@pytest.mark.skipif(not _file_inputs_available(), reason="file inputs not available yet")
def test_monitor_replays_a_candump_file(tmp_path: Path) -> None:
    from analyzer.sources import open_source

    log = tmp_path / "sample.log"
    lines = [
        f"({f.time:.6f}) can0 {f.can_id:08X}#{f.data.hex().upper()}"
        for f in session(T0, 2.0, foreign_per_s=50)
    ]
    log.write_text("\n".join(lines) + "\n", encoding="utf-8")
    source = open_source(f"file:{log}")
    capture = Capture(source, [], batch_interval=0.02)
    bridge = TuiBridge()
    add_sink(capture, bridge)
    app = MonitorApp(bridge, capture=capture, source_label=f"file:{log}")

    async def body() -> None:
        capture.start()
        async with app.run_test(size=(120, 40)) as pilot:
            await wait_for(pilot, lambda: app.state.source_ended)
            app.refresh_view()
            await pilot.pause()
            text = screen_text(app)
            assert app.state.total.frames == len(lines)
            assert app.state.attitude is not None
            assert "0x030F0001" in text and "waypoint" in text
            await pilot.press("q")

    asyncio.run(body())


def test_monitor_command_arguments() -> None:
    parser = build_parser()
    args = parser.parse_args(["monitor", "--source", "file:x.log", "--speed", "max"])
    assert args.source == "file:x.log"
    assert monitor.parse_speed("max") is None
    assert monitor.parse_speed("2.5") == 2.5
    with pytest.raises(UsageError):
        monitor.parse_speed("fast-ish")
    with pytest.raises(UsageError):
        monitor.parse_speed("-1")
    with pytest.raises(UsageError):
        monitor.run(argparse.Namespace(source="tcp:127.0.0.1:1", speed="2"))


def test_run_app_attaches_starts_and_stops_the_capture(monkeypatch: pytest.MonkeyPatch) -> None:
    frames = list(session(T0, 1.0))
    sink = RecordingSink()
    capture = Capture(ListSource(frames), [sink], batch_interval=0.02)
    seen: list[int] = []

    async def auto_pilot(pilot: Pilot[Any]) -> None:
        app = pilot.app
        assert isinstance(app, MonitorApp)
        await wait_for(pilot, lambda: app.state.total.frames == len(frames))
        seen.append(app.state.total.frames)
        await pilot.press("q")

    def headless_run(self: MonitorApp) -> int | None:
        return App.run(self, headless=True, size=(120, 40), auto_pilot=auto_pilot)

    monkeypatch.setattr(MonitorApp, "run", headless_run)
    assert run_app(capture, recording="x.mcap", source_label="test:list") == 0
    assert seen == [len(frames)]
    assert sink.closed and not capture.running
