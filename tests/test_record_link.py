"""`record` tells the user what the link does, and fails when it never received anything."""

from __future__ import annotations

import io
import os
import socket
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from analyzer.commands.record import LinkWatch, StatusLine
from analyzer.link_status import LinkStatus
from analyzer.pipeline import Batch
from analyzer.protocol.types import LINK, Event, diagnostic
from analyzer.sources.base import link_event
from analyzer.tally import Tally

ROOT = Path(__file__).resolve().parent.parent
T0 = 1_700_000_000.0


def free_loopback_port() -> int:
    """A loopback port nothing listens on (bound once, then released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def link(t: float, state: str, detail: str, **extra: Any) -> Event:
    return diagnostic(t, "tcp", LINK, detail, state=state, **extra)


def test_link_status_says_refused_then_counts_down_the_retry() -> None:
    status = LinkStatus()
    assert not status.seen
    status.fold(
        [
            link(T0, "connect_failed", "cannot connect to 127.0.0.1:9: connection refused"),
            link(T0, "reconnecting", "reconnecting in 2.0 s", retry_in_s=2.0),
        ]
    )
    assert status.failing and not status.good
    refused = "cannot connect to 127.0.0.1:9: connection refused"
    assert status.describe(T0 + 0.5) == f"{refused}; retrying in 1.5 s"
    assert status.describe(T0 + 2.5) == f"{refused}; connecting again"
    status.note(link(T0 + 2.6, "connected", "connected to 127.0.0.1:9"))
    assert status.good and status.describe(T0 + 3) == "connected to 127.0.0.1:9"
    status.note(link(T0 + 9, "overflow", "dropped 3 frame(s)"))  # no change of link state
    assert status.describe(T0 + 9) == "connected to 127.0.0.1:9"
    status.fold(
        [
            link(T0 + 10, "lost", "connection lost: reset by peer"),
            link(T0 + 10, "reconnecting", "reconnecting in 0.5 s", retry_in_s=0.5),
        ]
    )
    gone = "(gone 0.2 s, since 22:13:30.000Z)"
    assert status.describe(T0 + 10.2) == f"connection lost: reset by peer {gone}; retrying in 0.3 s"
    status.fold(
        [
            link(T0 + 10.5, "connect_failed", "cannot connect to 127.0.0.1:9: timed out"),
            link(T0 + 10.5, "reconnecting", "reconnecting in 1.0 s", retry_in_s=1.0),
        ]
    )
    assert status.describe(T0 + 11.0) == (
        "cannot connect to 127.0.0.1:9: timed out (gone 1.0 s, since 22:13:30.000Z); "
        "retrying in 0.5 s"
    )
    status.note(link(T0 + 12, "connected", "connected to 127.0.0.1:9 again after 2.0 s without it"))
    assert status.describe(T0 + 20) == (
        "connected to 127.0.0.1:9 again after 2.0 s without it "
        "(lost 22:13:30.000Z, back 22:13:32.000Z)"
    )
    status.note(link(T0 + 30, "lost", "connection lost: timed out"))  # a second loss
    assert status.describe(T0 + 31) == (
        "connection lost: timed out (gone 1.0 s, since 22:13:50.000Z)"
    )


class Stats:
    elapsed_s = 1.0
    frames = chunks = bytes = events = diagnostics = dropped = 0
    frames_per_s = bytes_per_s = 0.0

    def __init__(self) -> None:
        self.tally = Tally()


class FakeCapture:
    def __init__(self) -> None:
        self.stats = Stats()
        self.error = None


def test_status_line_shows_connecting_then_the_link_message() -> None:
    stream = io.StringIO()
    watch = LinkWatch()
    line = StatusLine(stream, "out.mcap", watch, waiting="connecting to 127.0.0.1:9")
    line.capture = FakeCapture()
    assert "[connecting to 127.0.0.1:9]" in line.line()
    batch = Batch(
        [],
        [
            link_event(
                "tcp", "cannot connect to 127.0.0.1:9: connection refused", "connect_failed"
            ),
            link_event("tcp", "reconnecting in 5.0 s", "reconnecting", retry_in_s=5.0),
        ],
        T0,
    )
    watch.handle(batch)
    line.handle(batch)  # not a terminal: a change of link state is written at once
    written = stream.getvalue()
    assert "[cannot connect to 127.0.0.1:9: connection refused; retrying in " in written
    assert written.count("\n") == 1
    line.handle(Batch([], [], T0))  # the same state again: no new line before the interval
    assert stream.getvalue() == written
    assert watch.last_words() == "cannot connect to 127.0.0.1:9: connection refused"


@pytest.mark.slow
def test_record_from_a_port_nobody_listens_on_says_refused_and_exits_1(tmp_path: Path) -> None:
    port = free_loopback_port()
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "analyzer",
            "record",
            "--source",
            f"tcp:127.0.0.1:{port}",
            "-o",
            "x.mcap",
            "--duration",
            "1",
        ],
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        capture_output=True,
        text=True,
        timeout=60,
        encoding="utf-8",
    )
    assert proc.returncode == 1, proc.stderr
    lines = proc.stderr.splitlines()
    status = [line for line in lines if line.startswith("recording x.mcap")]
    assert status and "connection refused" in status[0] and "retrying in" in status[0]
    assert any(
        line.startswith(f"gimbal-analyzer record: nothing was received from tcp:127.0.0.1:{port}")
        and "(last link message: cannot connect to" in line
        and "connection refused)" in line
        for line in lines
    ), proc.stderr
    assert (tmp_path / "x.mcap").exists()  # the link diagnostics are kept


def test_record_tui_without_a_terminal_refuses_at_once(tmp_path: Path) -> None:
    port = free_loopback_port()
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "analyzer",
            "record",
            "--tui",
            "--source",
            f"tcp:127.0.0.1:{port}",
            "-o",
            "x.mcap",
        ],
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdin=subprocess.DEVNULL,
        capture_output=True,
        timeout=60,  # it used to hang, writing screen codes into the pipe
    )
    assert proc.returncode == 2
    assert proc.stdout == b""  # no screen codes in the redirected output
    assert b"record --tui needs a terminal" in proc.stderr
    assert b"\x1b[" not in proc.stderr
    assert not (tmp_path / "x.mcap").exists()


def test_the_monitor_status_bar_says_the_same() -> None:
    from analyzer.tui.state import MonitorState
    from analyzer.tui.status_bar import StatusInfo, render_status

    state = MonitorState()
    refused = "cannot connect to 127.0.0.1:9: connection refused"
    events = [
        link(T0, "connect_failed", refused),
        link(T0, "reconnecting", "reconnecting in 4.0 s", retry_in_s=4.0),
    ]
    state.fold(Batch([], events, T0), T0)
    state.advance(T0 + 1.0)
    text = render_status(state, StatusInfo(source="tcp:127.0.0.1:9")).plain
    assert f"{refused}; retrying in 3.0 s" in text


def test_the_monitor_status_bar_says_how_long_an_adapter_was_gone() -> None:
    from analyzer.tui.state import MonitorState
    from analyzer.tui.status_bar import StatusInfo, render_status

    state = MonitorState()
    source = "can:slcan:/dev/serial/by-id/usb-canable.io_CANable_8c005eb_0037001A5948-if00"
    lost = f"{source}@1000000 lost: Could not read from serial device: Input/output error"
    state.fold(
        Batch(
            [],
            [
                link(T0, "lost", lost),
                link(T0, "reconnecting", "reconnecting in 0.5 s", retry_in_s=0.5),
            ],
            T0,
        ),
        T0,
    )
    state.advance(T0 + 2.0)
    text = render_status(state, StatusInfo(source=source)).plain
    assert f"{lost} (gone 2.0 s, since 22:13:20.000Z); connecting again" in text
    back = f"opened {source}@1000000 (listen-only) again after 5.5 s without it"
    state.fold(Batch([], [link(T0 + 5.5, "open", back, down_s=5.5, lost_at=T0)], T0 + 5.5), T0)
    state.advance(T0 + 6.0)
    text = render_status(state, StatusInfo(source=source)).plain
    assert f"{back} (lost 22:13:20.000Z, back 22:13:25.500Z)" in text


def test_the_status_line_shows_the_bus_state_in_the_status_bar_s_words() -> None:
    # SocketCAN error frames (linux/can/error.h): bus-off, then restarted, then a missing
    # ACK, through the same pipeline and counters as a capture.
    from analyzer.pipeline import Pipeline
    from analyzer.protocol.types import CanFrame
    from analyzer.tui.state import MonitorState
    from analyzer.tui.status_bar import StatusInfo, render_status

    line = StatusLine(io.StringIO(), "out.mcap", LinkWatch())
    line.capture = FakeCapture()
    pipeline = Pipeline([])
    ok = CanFrame(T0, 0xF01, bytes(8), True, "can0")
    pipeline.feed([ok])
    line.capture.stats.tally = pipeline.snapshot()
    assert "CAN" not in line.line() and "error frame" not in line.line()  # none seen yet

    errors = [
        CanFrame(T0 + 1, 0x040, bytes(8), True, "can0", is_error=True),  # bus-off
        CanFrame(T0 + 2, 0x100, bytes(8), True, "can0", is_error=True),  # restarted
        CanFrame(T0 + 3, 0x020, bytes(8), True, "can0", is_error=True),  # no ACK
    ]
    pipeline.feed(errors)
    batch = pipeline.deliver(T0 + 3)
    line.capture.stats.tally = pipeline.snapshot()
    words = "CAN error-active  worst bus-off 22:13:21.000Z  3 error frames: bus-off 1, "
    assert words in line.line()
    state = MonitorState()
    state.fold(batch, wall_time=T0 + 3)
    bar = render_status(state, StatusInfo(source="can:socketcan:can0")).plain
    assert words in bar  # what the monitor's status bar says, word for word
