"""Runs the monitor on a capture: attaches the bridge, starts the capture, stops it on quit."""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from analyzer.pipeline import Sink
from analyzer.timefmt import UTC, TimeZone
from analyzer.tui.bridge import TuiBridge
from analyzer.tui.monitor_app import REFRESH_HZ, CaptureControl, MonitorApp, RefreshStats
from analyzer.tui.monitor_layout import PAGES, is_paged

# The names importers know from here; most are defined in the modules above.
__all__ = [
    "PAGES",
    "REFRESH_HZ",
    "CaptureControl",
    "MonitorApp",
    "RefreshStats",
    "StartStopCapture",
    "add_sink",
    "is_paged",
    "run_app",
]


def add_sink(capture: object, sink: Sink) -> None:
    """Attach a sink to a capture that may already have others."""
    adder = getattr(capture, "add_sink", None)
    if callable(adder):
        adder(sink)
        return
    sinks = getattr(capture, "sinks", None)
    if isinstance(sinks, list):
        sinks.append(sink)
        return
    raise TypeError("the capture accepts no extra sinks")


class StartStopCapture(CaptureControl, Protocol):
    def start(self) -> None: ...


def run_app(
    capture: StartStopCapture,
    *,
    recording: str | None = None,
    source_label: str = "",
    exit_when_done: bool = False,
    live_status: Callable[[], tuple[str, bool]] | None = None,
    zone: TimeZone = UTC,
) -> int:
    """Show the monitor for ``capture``: attach the bridge, start, run the UI, stop on quit.

    Times are shown in ``zone`` (``--local-time``: local time). With ``exit_when_done``
    the UI also quits by itself when the capture ends (a ``--duration`` ran out, a
    replayed file ended); otherwise it stays to be read.

    The capture is stopped and joined (so every sink, the recording included, is
    finalised) whether the user quits (q, Ctrl+C, SIGTERM) or the UI fails. Returns 0,
    or 1 when the capture ended with an error (left in ``capture.error`` for the caller
    to report once the terminal is restored).
    """
    bridge = TuiBridge()
    add_sink(capture, bridge)
    app = MonitorApp(
        bridge,
        source_label=source_label,
        recording=recording,
        capture=capture,
        handle_sigterm=True,
        exit_when_done=exit_when_done,
        live_status=live_status,
        zone=zone,
    )
    capture.start()
    try:
        result = app.run()
    finally:
        app.stop_capture()
    if getattr(capture, "error", None) is not None:
        return 1
    return int(result or 0)
