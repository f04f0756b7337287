"""A full disk while recording or converting: stop at once, say why, keep every complete chunk."""

from __future__ import annotations

import errno
import io
import os
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pytest

from analyzer import output_file
from analyzer.capture import Capture
from analyzer.mcapio.read.reader import McapRecording, read_items
from analyzer.mcapio.write.sink import McapSink
from analyzer.protocol.types import CanFrame

ROOT = Path(__file__).resolve().parent.parent
T0 = 1_715_680_800.0
FEEDBACK = "0F040CFE00000000"

try:
    import resource
except ImportError:  # not POSIX
    resource = None  # type: ignore[assignment]

needs_rlimit = pytest.mark.skipif(
    resource is None or not hasattr(resource, "RLIMIT_FSIZE"),
    reason="needs RLIMIT_FSIZE to make a size-limited file",
)


def _candump(path: Path, lines: int) -> None:
    path.write_text(
        "".join(f"({T0 + n * 0.002:.6f}) can0 0F01#{FEEDBACK}\n" for n in range(lines)),
        encoding="utf-8",
    )


def _run_limited(args: list[str], limit: int, cwd: Path) -> subprocess.CompletedProcess[str]:
    """The CLI in a process whose files cannot grow past ``limit`` bytes (EFBIG, like a full
    disk: Python ignores SIGXFSZ, so the write fails instead of killing the process)."""

    def limit_size() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1", PYTHONPATH=str(ROOT))
    return subprocess.run(
        [sys.executable, "-m", "analyzer", *args],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        preexec_fn=limit_size,
        encoding="utf-8",
    )


@pytest.mark.slow
@needs_rlimit
def test_record_on_a_full_disk_keeps_every_complete_chunk_and_says_so(tmp_path: Path) -> None:
    log = tmp_path / "flight.log"
    _candump(log, 40_000)
    out = tmp_path / "flight.mcap"
    done = _run_limited(["record", "--source", f"file:{log}", "-o", str(out)], 300_000, tmp_path)
    assert done.returncode == 1, done.stderr
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith("gimbal-analyzer record: error: disk full: cannot write"), last
    assert "File too large" in last
    kept = int(last.split("; ")[-1].split(" messages up to ")[0])
    assert kept > 1000
    assert out.stat().st_size <= 300_000
    recording = McapRecording(out)
    assert sum(1 for _ in recording.messages()) == kept
    frames = list(read_items(out))
    assert frames and frames[0].time == pytest.approx(T0)
    # the frames kept are the first ones, in order, none missing
    assert [round((f.time - T0) / 0.002) for f in frames] == list(range(len(frames)))
    # the status line (not a terminal: its last update) says why the capture stopped
    assert "STOPPED: disk full" in done.stderr


@pytest.mark.slow
@needs_rlimit
def test_record_on_a_disk_already_full_leaves_no_file_behind(tmp_path: Path) -> None:
    log = tmp_path / "flight.log"
    _candump(log, 100)
    out = tmp_path / "flight.mcap"
    done = _run_limited(["record", "--source", f"file:{log}", "-o", str(out), "-q"], 4, tmp_path)
    assert done.returncode == 1, done.stderr
    assert "disk full: cannot write" in done.stderr and "nothing was kept" in done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["flight.log"]
    rerun = _run_limited(
        ["record", "--source", f"file:{log}", "-o", str(out), "-q"], 10**9, tmp_path
    )
    assert rerun.returncode == 0, rerun.stderr


@needs_rlimit
def test_convert_on_a_full_disk_fails_and_leaves_nothing(tmp_path: Path) -> None:
    log = tmp_path / "flight.log"
    _candump(log, 20_000)
    out = tmp_path / "flight.mcap"
    out.write_bytes(b"an older conversion")
    args = ["convert", str(log), "-o", str(out), "--force", "-q"]
    done = _run_limited(args, 100_000, tmp_path)
    assert done.returncode == 1, done.stderr
    assert "disk full: cannot write" in done.stderr
    assert "Traceback" not in done.stderr
    assert out.read_bytes() == b"an older conversion"  # replaced only by a complete file
    assert sorted(p.name for p in tmp_path.iterdir()) == ["flight.log", "flight.mcap"]


class _FullDisk(io.FileIO):
    """A file on a disk that fills up after ``room`` bytes (the write that crosses it is cut)."""

    room = 0
    failed_at: float | None = None

    def write(self, data: Any) -> int:
        left = self.room - self.tell()
        if len(data) > left:
            if left > 0:
                super().write(bytes(data)[:left])
            if _FullDisk.failed_at is None:
                _FullDisk.failed_at = time.monotonic()
            raise OSError(errno.ENOSPC, "No space left on device")
        return super().write(data)


class _EndlessBus:
    """A live source that never ends: one attitude frame every 2 ms of its own clock."""

    description = "test bus"
    source_name = "test"

    def __init__(self) -> None:
        self.n = 0
        self.closed = threading.Event()
        self.closed_at = 0.0

    def read(self, timeout: float) -> list[Any]:
        time.sleep(min(timeout, 0.005))
        frames = [
            CanFrame(T0 + (self.n + k) * 0.002, 0x0F01, bytes.fromhex(FEEDBACK)) for k in range(20)
        ]
        self.n += 20
        return frames

    def close(self) -> None:
        self.closed_at = time.monotonic()
        self.closed.set()


@pytest.mark.slow
def test_a_write_error_in_the_flush_thread_stops_the_capture(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(_FullDisk, "room", 400_000)
    monkeypatch.setattr(_FullDisk, "failed_at", None)
    monkeypatch.setattr(output_file, "FileIO", _FullDisk)
    path = tmp_path / "live.mcap"
    # chunks never fill up: only the timed flush (the background thread) writes them
    sink = McapSink(path, metadata={"source": "test"}, chunk_size=1 << 30, flush_interval=0.1)
    source = _EndlessBus()
    capture = Capture(source, [sink])
    capture.start()
    assert source.closed.wait(20), "the capture went on after the disk filled up"
    capture.wait()
    assert _FullDisk.failed_at is not None
    assert source.closed_at - _FullDisk.failed_at < 1.0  # stopped within a second
    assert capture.stop_reason == "error"
    assert capture.error is not None
    assert str(capture.error).startswith(f"disk full: cannot write {path}")
    assert sink.error is not None and f"{sink.kept_messages} messages up to" in sink.error
    assert sink.kept_messages > 0
    assert sum(1 for _ in McapRecording(path).messages()) == sink.kept_messages
