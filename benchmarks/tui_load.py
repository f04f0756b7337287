"""Load benchmark of the monitor TUI: a capture at ~8,000 frames/s into the headless app.

A paced source hands out CAN frames at the bus rate (timestamped with the wall clock, as a
live interface does); the real Capture decodes them in its thread and passes batches to
the app's bridge; the app (Textual, headless, 120x40) folds and redraws as it would on a
terminal. Reported:

- frames/s offered and frames/s the app took in (folded into its screen model),
- how stale the screen is: at every redraw, wall time minus the time of the newest frame
  shown (capture batching + hand-over + waiting for the next redraw),
- UI thread busy time (folding, drawing), process CPU, bridge backlog, skipped batches,
- the model's fold throughput alone (frames/s one core folds, no UI).

Run:  python benchmarks/tui_load.py [--seconds 20] [--rate 8000]
"""

from __future__ import annotations

import argparse
import asyncio
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from analyzer.capture import Capture
from analyzer.pipeline import Batch, RawItem
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.types import CanFrame
from analyzer.tui.app import MonitorApp, add_sink
from analyzer.tui.bridge import TuiBridge
from analyzer.tui.demo_traffic import session
from analyzer.tui.state import MonitorState

PROTOCOL_RATE = 50  # frames/s of gimbal + UAV traffic in the demo session (approx.)


class PacedSource:
    """Frames of a recorded-like session, released when their time comes (like a live bus)."""

    description = "bench:paced"
    source_name = "bench"

    def __init__(self, frames: list[tuple[float, int, bytes]]) -> None:
        self.frames = frames
        self.index = 0
        self.start = 0.0
        self.released = 0

    def read(self, timeout: float) -> list[CanFrame]:
        now = time.time()
        if not self.start:
            self.start = now
        if self.index >= len(self.frames):
            raise EOFError
        elapsed = now - self.start
        out: list[CanFrame] = []
        frames = self.frames
        i = self.index
        start = self.start
        while i < len(frames) and frames[i][0] <= elapsed and len(out) < 5000:
            rel, can_id, data = frames[i]
            out.append(CanFrame(start + rel, can_id, data, channel="can0"))
            i += 1
        self.index = i
        self.released += len(out)
        if not out:
            time.sleep(min(timeout, 0.005))
        return out

    def close(self) -> None:
        pass


class MeasuredApp(MonitorApp):
    """The monitor app, timing its fold and redraw work and the staleness of each redraw."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.fold_s = 0.0
        self.draw_s = 0.0
        self.staleness: list[float] = []
        self.backlogs: list[int] = []

    def pull(self) -> int:
        t = time.perf_counter()
        n = super().pull()
        self.fold_s += time.perf_counter() - t
        return n

    def refresh_view(self) -> None:
        t = time.perf_counter()
        super().refresh_view()
        self.draw_s += time.perf_counter() - t
        newest = self.state.last_item_time
        running = bool(getattr(self.capture, "running", False))
        if newest is not None and not self.paused and running:
            self.staleness.append(time.time() - newest)
        self.backlogs.append(self.bridge.backlog)


def percentile(values: list[float], q: float) -> float:
    if not values:
        return float("nan")
    ordered = sorted(values)
    return ordered[min(int(q * len(ordered)), len(ordered) - 1)]


async def run_app_under_load(seconds: float, rate: float, ids: int = 40) -> dict[str, Any]:
    foreign = max(rate - PROTOCOL_RATE, 0)
    frames = [
        (f.time, f.can_id, f.data)
        for f in session(0.0, seconds, foreign_per_s=foreign, foreign_ids=ids)
    ]
    source = PacedSource(frames)
    bridge = TuiBridge()
    capture = Capture(source, [], batch_interval=0.05)
    add_sink(capture, bridge)
    app = MeasuredApp(bridge, capture=capture, source_label=source.description)
    async with app.run_test(size=(120, 40)) as pilot:
        await pilot.pause()
        cpu0 = time.process_time()
        wall0 = time.perf_counter()
        capture.start()
        while capture.running:
            await asyncio.sleep(0.1)
        wall = time.perf_counter() - wall0
        cpu = time.process_time() - cpu0
        await pilot.pause(0.3)
        app.refresh_view()
        result = {
            "seconds": wall,
            "frames_offered": len(frames),
            "offered_fps": len(frames) / wall,
            "frames_taken": app.state.total.frames,
            "taken_fps": app.state.total.frames / wall,
            "dropped_batches": app.state.dropped_batches,
            "batches": app.stats.batches,
            "messages": app.stats.messages,
            "refreshes": app.stats.refreshes,
            "refresh_hz": app.stats.refreshes / wall,
            "staleness_p50_ms": 1000 * percentile(app.staleness, 0.5),
            "staleness_p95_ms": 1000 * percentile(app.staleness, 0.95),
            "staleness_max_ms": 1000 * max(app.staleness, default=float("nan")),
            "ui_busy_pct": 100 * (app.fold_s + app.draw_s) / wall,
            "fold_pct": 100 * app.fold_s / wall,
            "draw_pct": 100 * app.draw_s / wall,
            "cpu_pct_of_one_core": 100 * cpu / wall,
            "max_backlog_batches": max(app.backlogs, default=0),
            "log_entries": len(app.state.all_log),
            "rows": len(app.state.rows),
        }
        await pilot.press("q")
    return result


def fold_throughput(n_frames: int = 200_000) -> float:
    """Frames/s the screen model folds on one core (pre-decoded batches, no UI)."""
    frames = list(session(0.0, n_frames / 8000, foreign_per_s=8000 - PROTOCOL_RATE))
    decoder = ProtocolDecoder()
    batches: list[Batch] = []
    for i in range(0, len(frames), 400):
        chunk: list[RawItem] = list(frames[i : i + 400])
        events = [e for f in chunk for e in decoder.feed(f)]
        batches.append(Batch(chunk, events, chunk[-1].time))
    state = MonitorState()
    t = time.perf_counter()
    for batch in batches:
        state.fold(batch)
    return len(frames) / (time.perf_counter() - t)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--rate", type=float, default=8000.0, help="frames/s offered")
    parser.add_argument("--ids", type=int, default=40, help="foreign CAN IDs on the bus")
    args = parser.parse_args()
    print(f"model fold alone: {fold_throughput():,.0f} frames/s on one core")
    result = asyncio.run(run_app_under_load(args.seconds, args.rate, args.ids))
    width = max(len(k) for k in result)
    for key, value in result.items():
        shown = f"{value:,.1f}" if isinstance(value, float) else f"{value:,}"
        print(f"{key:<{width}}  {shown}")
    lost = result["frames_offered"] - result["frames_taken"]
    print(f"frames not shown: {lost}  (median staleness {result['staleness_p50_ms']:.0f} ms)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
