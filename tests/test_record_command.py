"""`record` as a real process against a fake IDU on loopback: kill -9, SIGTERM and Ctrl-C."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from mcap.reader import make_reader

from analyzer.mcapio.read.reader import McapRecording, read_events, read_items
from analyzer.protocol.feedback import encode_attitude
from analyzer.protocol.types import StreamChunk
from tests.mcap_doctor import examine

ROOT = Path(__file__).resolve().parent.parent
SEND_INTERVAL = 0.01
# The recorder flushes every 0.5 s; messages older than this must survive kill -9
# (generous, so a loaded machine does not make the test flaky).
SURVIVAL_AGE = 1.5

pytestmark = pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="needs POSIX signals")


class FakeIdu:
    """A TCP server that streams attitude feedback, yaw = message number / 100 deg."""

    def __init__(self) -> None:
        self.server = socket.create_server(("127.0.0.1", 0))
        self.port = self.server.getsockname()[1]
        self.sent: list[tuple[float, bytes]] = []  # (time sent, frame)
        self.connected = threading.Event()
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        self.server.settimeout(10)
        try:
            conn, _ = self.server.accept()
        except OSError:
            return
        self.connected.set()
        with conn:
            n = 0
            while not self.stop.is_set():
                frame = encode_attitude(pitch_deg=-5.0, yaw_deg=n / 100, motor_yaw_deg=0.0)
                try:
                    conn.sendall(frame)
                except OSError:
                    return
                self.sent.append((time.time(), frame))
                n = (n + 1) % 36000
                time.sleep(SEND_INTERVAL)

    def close(self) -> None:
        self.stop.set()
        self.server.close()
        self.thread.join(5)


def _start_recorder(port: int, path: Path) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
        [
            sys.executable,
            "-m",
            "analyzer",
            "record",
            "--source",
            f"tcp:127.0.0.1:{port}",
            "-o",
            str(path),
        ],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )


def _record(tmp_path: Path, seconds: float, sig: int) -> tuple[Path, FakeIdu, float, bytes, int]:
    idu = FakeIdu()
    path = tmp_path / "flight.mcap"
    proc = _start_recorder(idu.port, path)
    try:
        if not idu.connected.wait(20):
            proc.kill()
            _, err = proc.communicate()
            pytest.fail(f"the recorder did not connect: {err.decode()}")
        time.sleep(seconds)
        signalled = time.time()
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        idu.close()
    return path, idu, signalled, err, proc.returncode


def _yaws_in_events(path: Path) -> set[float]:
    return {
        e.fields["yaw_deg"]
        for e in read_events(path)
        if e.topic == "/gimbal/attitude" and e.source.startswith("tcp")
    }


@pytest.mark.slow
def test_kill_9_keeps_everything_older_than_a_second(tmp_path: Path) -> None:
    path, idu, killed, _, code = _record(tmp_path, 2.5, signal.SIGKILL)
    assert code == -signal.SIGKILL
    recording = McapRecording(path)
    items = read_items(path)
    stream = b"".join(i.data for i in items if isinstance(i, StreamChunk))
    if recording.recovered:  # killed in the middle of a write: no summary, recovered
        assert items.recovered and "recovered" in items.note
    else:  # killed between flushes: the provisional summary is there, the closing stats not
        assert "gimbal-analyzer.stats" not in recording.metadata()
        assert "NOT CLOSED" in _info(path)
    old = [frame for sent, frame in idu.sent if sent < killed - SURVIVAL_AGE]
    assert len(old) > 50
    # The raw channel holds every old frame, byte for byte and in order.
    assert stream.startswith(b"".join(old))
    # And the decoded channel holds the matching attitude events.
    yaws = _yaws_in_events(path)
    expected = {round(n / 100, 2) for n in range(len(old))}
    assert expected <= yaws
    # What survived is compressed and in log-time order.
    diagnosis = examine(path)
    assert diagnosis.warnings == [] and diagnosis.compressions == {"zstd"}
    if recording.recovered:
        assert all("DataEnd" in e or "Footer" in e or "ends inside" in e for e in diagnosis.errors)
    else:
        assert diagnosis.errors == []


def _info(path: Path) -> str:
    done = subprocess.run(
        [sys.executable, "-m", "analyzer", "info", str(path)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
        encoding="utf-8",
    )
    return done.stdout


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_sigterm_and_ctrl_c_finish_the_file(tmp_path: Path, sig: int) -> None:
    path, idu, signalled, err, code = _record(tmp_path, 1.2, sig)
    assert code == 0, err.decode()
    assert b"recorded" in err
    recording = McapRecording(path)
    assert not recording.recovered
    with open(path, "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        assert summary.statistics.message_count > 0
        messages = list(reader.iter_messages())
    assert len(messages) == summary.statistics.message_count
    diagnosis = examine(path)
    assert diagnosis.errors == [] and diagnosis.warnings == []
    sent = [frame for t, frame in idu.sent if t < signalled - 0.3]
    stream = b"".join(i.data for i in read_items(path) if isinstance(i, StreamChunk))
    assert stream.startswith(b"".join(sent))
    meta = recording.metadata()
    assert meta["gimbal-analyzer"]["source"] == f"tcp:127.0.0.1:{idu.port}"
    assert "gimbal-analyzer.stats" in meta


def test_bad_source_is_a_usage_error(tmp_path: Path) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "analyzer", "record", "--source", "nope:x", "-o", "x.mcap"],
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        capture_output=True,
        timeout=30,
    )
    assert proc.returncode == 2
    assert b"bad source" in proc.stderr
    assert not (tmp_path / "x.mcap").exists()


def test_an_existing_recording_is_not_overwritten(tmp_path: Path) -> None:
    from analyzer.cli import main

    existing = tmp_path / "flight.mcap"
    existing.write_bytes(b"earlier flight")
    assert main(["record", "--source", "tcp:127.0.0.1:9", "-o", str(existing)]) == 2
    assert existing.read_bytes() == b"earlier flight"
