"""Render the monitor's screen as text from a minute of synthetic traffic (the manual).

Run ``python -m analyzer.tui.demo_screen [WIDTH HEIGHT] [--svg FILE]``; the app runs
headless with an injected clock, so the output is the same on every run (times are shown
in local time). ``--svg`` also writes Textual's own screenshot of the screen (the
manual's picture of the monitor is made from it).
"""

from __future__ import annotations

import asyncio
import sys

from analyzer.pipeline import Batch, RawItem
from analyzer.protocol.codec import encode_command
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.ids import CONTROL_ID, FEEDBACK_ID
from analyzer.protocol.types import LINK, CanFrame, diagnostic
from analyzer.tui.app import MonitorApp
from analyzer.tui.bridge import TuiBridge
from analyzer.tui.demo_traffic import session
from analyzer.tui.screen_text import screen_text

T0 = 1_717_400_000.0
SECONDS = 60.0
BATCH_S = 0.05


def demo_frames() -> list[CanFrame]:
    """A minute of traffic with a few faults: a corrupted feedback segment, an unknown command."""
    frames = list(session(T0, SECONDS, foreign_per_s=400, foreign_ids=8))
    out: list[CanFrame] = []
    corrupted = 0
    for frame in frames:
        offset = frame.time - T0
        if frame.can_id == FEEDBACK_ID and corrupted < 3 and offset > 20 * (corrupted + 1):
            frame = CanFrame(frame.time, frame.can_id, bytes([0xFF]) + frame.data[1:])
            corrupted += 1
        out.append(frame)
    out.append(CanFrame(T0 + 57.3, CONTROL_ID, bytes([0x0F, 0x42, 0, 0, 0, 0, 0, 0])))
    out.append(CanFrame(T0 + 59.9, CONTROL_ID, encode_command("zoom", action="zoom_in")))
    out.sort(key=lambda f: f.time)
    return out


async def render(width: int = 120, height: int = 40, svg: str | None = None) -> str:
    frames = demo_frames()
    now = [T0]
    bridge = TuiBridge(max_backlog=100_000)
    app = MonitorApp(
        bridge,
        source_label="can:socketcan:can0",
        recording="flight.mcap",
        clock=lambda: now[0],
        file_size=lambda path: 4_812_345,
    )
    decoder = ProtocolDecoder()
    async with app.run_test(size=(width, height)) as pilot:
        link = diagnostic(T0, "can0", LINK, "opened socketcan can0 (listen-only)", state="open")
        bridge.handle(Batch([], [link], T0))
        start = 0
        end_time = T0 + BATCH_S
        while start < len(frames):
            stop = start
            while stop < len(frames) and frames[stop].time < end_time:
                stop += 1
            chunk: list[RawItem] = list(frames[start:stop])
            events = [e for f in frames[start:stop] for e in decoder.feed(f)]
            events += decoder.tick(end_time)
            bridge.handle(Batch(chunk, events, end_time))
            app.pull()
            start = stop
            end_time += BATCH_S
        now[0] = frames[-1].time + 0.1
        app.pull()
        app.refresh_view()
        await pilot.pause()
        if svg:
            with open(svg, "w", encoding="utf-8") as out:
                out.write(app.export_screenshot(title="gimbal-analyzer monitor"))
        return screen_text(app)


def main(argv: list[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    svg = None
    if "--svg" in args:
        at = args.index("--svg")
        svg = args[at + 1]
        del args[at : at + 2]
    width, height = (int(args[0]), int(args[1])) if len(args) >= 2 else (120, 40)
    print(asyncio.run(render(width, height, svg)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
