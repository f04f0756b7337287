"""`record --tui` in a real pseudo-terminal: the screen comes up, `q` quits, the file is final."""

from __future__ import annotations

import os
import select
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from analyzer.mcapio.read.reader import read_events

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "samples" / "flight-candump.log"

pytestmark = [
    pytest.mark.skipif(sys.platform == "win32", reason="needs a POSIX pty"),
    pytest.mark.slow,  # the monitor UI recording, seconds each
]


def read_until(
    fd: int, needle: bytes, timeout: float, stop: threading.Event | None = None
) -> bytes:
    """Everything the terminal shows until ``needle`` appears (or the time is up)."""
    seen = b""
    deadline = time.monotonic() + timeout
    while needle not in seen and time.monotonic() < deadline:
        if stop is not None and stop.is_set():
            break
        ready, _, _ = select.select([fd], [], [], 0.2)
        if ready:
            try:
                seen += os.read(fd, 65536)
            except OSError:
                break
    return seen


def test_record_tui_shows_the_screen_and_q_finalises_the_recording(tmp_path: Path) -> None:
    out = tmp_path / "watched.mcap"
    primary, secondary = os.openpty()
    env = {**os.environ, "TERM": "xterm-256color", "COLUMNS": "120", "LINES": "40"}
    env.pop("NO_COLOR", None)
    proc = subprocess.Popen(
        [sys.executable, "-m", "analyzer", "record", "--source", f"file:{SAMPLE}",
         "-o", str(out), "--tui"],
        stdin=secondary, stdout=secondary, stderr=secondary, cwd=ROOT, env=env,
        start_new_session=True,
    )  # fmt: skip
    os.close(secondary)
    try:
        screen = read_until(primary, b"Quit", timeout=30)
        assert b"Quit" in screen, screen[-2000:]
        # Keep reading the terminal, or the app blocks on a full pty buffer.
        stop = threading.Event()
        drain = threading.Thread(target=read_until, args=(primary, b"\0", 60, stop))
        drain.start()
        time.sleep(1.0)  # let the replay finish into the recording
        os.write(primary, b"q")
        assert proc.wait(timeout=30) == 0
        stop.set()
        drain.join()
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        os.close(primary)
    events = read_events(out)
    topics = [e.topic for e in events]
    assert not events.recovered, "the recording was not finalised"
    assert topics.count("/gimbal/command") == 45
    assert "/gimbal/attitude" in topics


def test_record_tui_with_a_duration_quits_by_itself(tmp_path: Path) -> None:
    out = tmp_path / "timed.mcap"
    primary, secondary = os.openpty()
    env = {**os.environ, "TERM": "xterm-256color", "COLUMNS": "120", "LINES": "40"}
    proc = subprocess.Popen(
        [sys.executable, "-m", "analyzer", "record", "--source", f"file:{SAMPLE}",
         "--speed", "4", "--duration", "2", "-o", str(out), "--tui"],
        stdin=secondary, stdout=secondary, stderr=secondary, cwd=ROOT, env=env,
        start_new_session=True,
    )  # fmt: skip
    os.close(secondary)
    stop = threading.Event()
    drain = threading.Thread(target=read_until, args=(primary, b"\0", 60, stop))
    drain.start()
    try:
        assert proc.wait(timeout=30) == 0  # no key pressed: the duration ends it
    finally:
        stop.set()
        drain.join()
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        os.close(primary)
    events = read_events(out)
    assert not events.recovered, "the recording was not finalised"
    commands = [e for e in events if e.topic == "/gimbal/command"]
    assert 0 < len(commands) < 45  # two seconds at 4x: about 8 s of a 20 s flight
