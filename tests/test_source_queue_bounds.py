"""The queue between a live source's I/O thread and the capture is bounded; drops are reported."""

from __future__ import annotations

import socket
import threading
import time
from typing import Any

import pytest

from analyzer.capture import Capture
from analyzer.pipeline import Batch
from analyzer.protocol.types import LINK, Event, StreamChunk
from analyzer.sources import base
from analyzer.sources.base import OVERFLOW, QueuedSource
from analyzer.sources.tcp_client import TcpClientSource

DEADLINE_S = 10.0


class Manual(QueuedSource):
    """A queued source fed by the test itself (no I/O thread)."""

    source_name = "manual"

    def put(self, data: bytes) -> None:
        self._put(StreamChunk(1.0, data, "manual"))


def overflow_events(items: list[Any]) -> list[Event]:
    return [
        i
        for i in items
        if isinstance(i, Event) and i.fields.get("kind") == LINK and i.fields["state"] == OVERFLOW
    ]


def test_a_full_queue_drops_counts_and_reports() -> None:
    source = Manual(max_items=5)
    for n in range(8):
        source.put(bytes([n]) * 10)
    items = source.read(0)
    chunks = [i for i in items if isinstance(i, StreamChunk)]
    assert [c.data[0] for c in chunks] == [0, 1, 2, 3, 4]  # the oldest are kept
    (report,) = overflow_events(items)
    assert items[-1] is report  # drained: the report follows what was kept
    assert "dropped 3 frame(s) / chunk(s) (30 bytes)" in report.fields["detail"]
    assert report.fields["byte_count"] == 30
    assert (source.dropped_items, source.dropped_bytes) == (3, 30)
    source.put(b"more")
    assert overflow_events(source.read(0)) == []  # reported once


def test_the_report_marks_the_place_of_the_gap(monkeypatch: pytest.MonkeyPatch) -> None:
    source = Manual(max_items=3)
    for n in range(4):
        source.put(bytes([n]))  # 3 is dropped
    monkeypatch.setattr(base, "MAX_ITEMS_PER_READ", 2)
    first = source.read(0)  # 0, 1: one still queued, the drop not yet reported
    assert [i.data for i in first] == [b"\x00", b"\x01"]
    source.put(b"\x04")  # room again: the report goes in before it
    rest = source.read(0) + source.read(0)
    assert [i.data if isinstance(i, StreamChunk) else "gap" for i in rest] == [
        b"\x02",
        "gap",
        b"\x04",
    ]


def test_bytes_are_bounded_as_well_as_items() -> None:
    source = Manual(max_items=1000, max_bytes=2500)
    for _ in range(5):
        source.put(bytes(1000))
    items = source.read(0)
    assert sum(len(i.data) for i in items if isinstance(i, StreamChunk)) == 2000
    assert source.dropped_bytes == 3000
    big = Manual(max_bytes=10)
    big.put(bytes(100))  # one oversized chunk still passes into an empty queue
    assert [len(i.data) for i in big.read(0)] == [100]


class HeldSink:
    """Holds the capture's first batch until released, as a slow disk would; ``holding``
    is set once it holds one."""

    def __init__(self) -> None:
        self.release = threading.Event()
        self.holding = threading.Event()
        self.events: list[Event] = []
        self.data = 0

    def handle(self, batch: Batch) -> None:
        self.holding.set()
        self.release.wait(DEADLINE_S)
        self.events.extend(batch.events)
        self.data += sum(len(i.data) for i in batch.items)

    def close(self) -> None:
        pass


def test_a_burst_from_the_idu_is_bounded_and_every_byte_is_accounted_for(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(base, "MAX_QUEUED_BYTES", 256 * 1024)
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]
    total = 8 * 1024 * 1024
    first = 16
    sent = threading.Event()
    sink = HeldSink()

    def idu() -> None:
        conn, _ = server.accept()
        with conn:
            # A first few bytes, then the burst once the capture is stuck in the slow
            # sink: sent at once, a fast capture could take it all into its first batch
            # before any queue filled up, and nothing would be dropped.
            conn.sendall(bytes(first))
            sink.holding.wait(DEADLINE_S)
            conn.sendall(bytes(total - first))
            sent.wait(DEADLINE_S)  # keep the link up until the test has looked

    thread = threading.Thread(target=idu, daemon=True)
    thread.start()
    source = TcpClientSource("127.0.0.1", port)
    capture = Capture(source, [sink], batch_interval=0.02)
    capture.start()
    deadline = time.monotonic() + DEADLINE_S
    # read by the capture (held in its batch), still queued, or dropped: nothing else
    while source.dropped_bytes + source._queued_bytes + capture.stats.bytes < total:
        assert time.monotonic() < deadline, "the burst did not arrive"
        assert source._queued_bytes <= 256 * 1024 + 65536  # never more than the bound
        time.sleep(0.01)
    sink.release.set()
    while capture.stats.dropped == 0 or source._queued_bytes:
        assert time.monotonic() < deadline
        time.sleep(0.01)
    capture.stop()
    capture.join(DEADLINE_S)
    sent.set()
    server.close()
    stats = capture.stats
    assert stats.dropped == source.dropped_items > 0
    assert sink.data + stats.dropped_bytes == total  # delivered or counted, nothing else
    reports = overflow_events(sink.events)
    assert reports and sum(e.fields["byte_count"] for e in reports) == stats.dropped_bytes


def test_the_status_line_and_the_monitor_show_drops() -> None:
    import io

    from analyzer.capture import CaptureStats
    from analyzer.commands.record import StatusLine
    from analyzer.tui.state import MonitorState
    from analyzer.tui.status_bar import StatusInfo, render_status

    class Stopped:
        stats = CaptureStats(frames=10, dropped=3, dropped_bytes=24)

    status = StatusLine(io.StringIO(), "x.mcap")
    status.capture = Stopped()
    assert "3 DROPPED" in status.line()
    status.capture.stats = CaptureStats(frames=10)
    assert "DROPPED" not in status.line()
    shown = render_status(MonitorState(), StatusInfo(source="tcp:x", dropped=1234)).plain
    assert "1,234 DROPPED" in shown
    assert "DROPPED" not in render_status(MonitorState(), StatusInfo(source="tcp:x")).plain
