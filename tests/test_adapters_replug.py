"""An adapter pulled out mid-capture and plugged in again: `record` goes on and loses nothing.

The adapters are pseudo-terminals behind /dev/serial/by-id style links (tests/slcan_adapter.py)
driven by python-can's own ``slcan`` interface and by pyserial, as on a field laptop.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import can
import jsonschema
import pytest
from mcap.reader import make_reader

from analyzer.mcapio.read.reader import read_replay
from analyzer.protocol.framing import wrap_control
from analyzer.protocol.types import LINK, CanFrame, Event, StreamChunk
from tests.mcap_doctor import examine
from tests.platforms import posix_signals, pseudo_terminals
from tests.slcan_adapter import PtyDevice, SlcanAdapter, by_id_name

# A simulated USB adapter is a pseudo-terminal; the recorder is stopped with SIGINT / SIGTERM;
# adapters unplugged and plugged again take seconds each.
pytestmark = [pseudo_terminals, posix_signals, pytest.mark.slow]

ROOT = Path(__file__).resolve().parent.parent
DEADLINE_S = 20.0
CANABLE = by_id_name("canable.io", "CANable_8c005eb", "0037001A5948")
FTDI = by_id_name("FTDI", "FT232R_USB_UART", "A10KZP4M")


def gimbal_frames(count: int, start: int = 0) -> list[tuple[int, bytes]]:
    """Frames the gimbal sends: a control frame stream with a changing yaw."""
    return [
        (0x00000F01, bytes([0x0F, 0x04, 0x0C, (i >> 8) & 0xFF, i & 0xFF, 0, 0, 0]))
        for i in range(start, start + count)
    ]


class Recorder:
    """``gimbal-analyzer record`` in a subprocess, its status lines collected as they come."""

    def __init__(self, cwd: Path, *args: str) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "analyzer", "record", *args],
            cwd=cwd,
            env={**os.environ, "PYTHONPATH": str(ROOT)},
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            encoding="utf-8",
        )
        self.lines: list[str] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stderr is not None
        for line in self.proc.stderr:
            self.lines.append(line.rstrip("\n"))

    def wait_for(self, words: str) -> str:
        deadline = time.monotonic() + DEADLINE_S
        while True:
            found = [line for line in self.lines if words in line]
            if found:
                return found[-1]
            assert self.proc.poll() is None or self._reader.is_alive(), "\n".join(self.lines)
            assert time.monotonic() < deadline, f"no {words!r} in:\n" + "\n".join(self.lines)
            time.sleep(0.05)

    def stop(self, signum: int) -> int:
        self.proc.send_signal(signum)
        code = self.proc.wait(DEADLINE_S)
        self._reader.join(DEADLINE_S)
        return code

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()


@pytest.fixture
def recorders() -> Iterator[list[Recorder]]:
    started: list[Recorder] = []
    yield started
    for recorder in started:
        recorder.kill()


def link_states(path: Path) -> list[Event]:
    return [
        item
        for item in read_replay(path)
        if isinstance(item, Event) and item.fields.get("kind") == LINK
    ]


def assert_diagnostics_match_their_schema(path: Path) -> None:
    """Every /diagnostics message validates against the JSON Schema its channel carries
    (what Foxglove reads), the fields of a link that came back included."""
    checked = 0
    with path.open("rb") as f:
        for schema, _channel, message in make_reader(f).iter_messages(topics=["/diagnostics"]):
            assert schema is not None
            data = json.loads(message.data)
            jsonschema.validate(data, json.loads(schema.data))
            schema_fields = json.loads(schema.data)["properties"]
            assert set(data) <= set(schema_fields), set(data) - set(schema_fields)
            checked += 1
    assert checked


def pull_out_and_back(
    device: PtyDevice, recorder: Recorder, spec: str, away_s: float = 0.0
) -> tuple[str, str]:
    """The cable pulled once the host has read everything, and plugged in again (a new tty
    behind the same by-id link) after a retry failed and ``away_s`` more seconds; returns
    record's status lines of the loss and of the return."""
    device.wait_read()
    device.unplug()
    lost = recorder.wait_for(f"{spec} lost: ")
    recorder.wait_for("cannot open " + spec)  # the link is gone: each retry says why
    time.sleep(away_s)
    device.plug()
    if isinstance(device, SlcanAdapter):
        device.wait_open()  # python-can waits 2 s after opening the port
    back = recorder.wait_for(" again after ")
    return lost, back


def test_the_simulated_adapter_answers_as_slcan_firmware(tmp_path: Path) -> None:
    adapter = SlcanAdapter(tmp_path / "serial" / "by-id" / CANABLE)
    adapter.plug()
    bus = can.Bus(
        interface="slcan",
        channel=str(adapter.link),
        bitrate=500_000,
        listen_only=True,
        sleep_after_open=0,
    )
    try:
        adapter.wait_open()
        assert (adapter.bitrate, adapter.mode) == (500_000, "listen-only")
        assert bus.get_version(2.0) == (10, 13)
        assert bus.get_serial_number(2.0) == "A1B2"
        adapter.frame(0x00000F01, bytes(range(8)))
        adapter.frame(0x123, b"\x01\x02", extended=False)
        first, second = bus.recv(2.0), bus.recv(2.0)
        assert first is not None and second is not None
        assert (first.arbitration_id, first.is_extended_id, bytes(first.data)) == (
            0x00000F01,
            True,
            bytes(range(8)),
        )
        assert (second.arbitration_id, second.is_extended_id, bytes(second.data)) == (
            0x123,
            False,
            b"\x01\x02",
        )
        bus.send(can.Message(arbitration_id=0x7FF, data=b"\x01", is_extended_id=False))
        time.sleep(0.1)
        assert adapter.answer(b"t7FF101") == b"\a"  # a listen-only adapter refuses to send
        assert adapter.answer(b"S8") == b"\a"  # no bitrate change while open
    finally:
        bus.shutdown()
        adapter.close()
    assert adapter.commands[:4] == [b"C", b"S6", b"", b"L"]
    assert adapter.transmit_requests == [b"t7FF101"]
    assert not adapter.link.exists()


def test_record_keeps_every_frame_across_an_unplugged_slcan_adapter(
    tmp_path: Path, recorders: list[Recorder]
) -> None:
    adapter = SlcanAdapter(tmp_path / "serial" / "by-id" / CANABLE)
    adapter.plug()
    before, after = gimbal_frames(300), gimbal_frames(329, start=300)
    spec = f"can:slcan:{adapter.link}@1000000"
    recorder = Recorder(tmp_path, "--source", spec, "-o", "flight.mcap")
    recorders.append(recorder)
    try:
        adapter.wait_open(DEADLINE_S)  # python-can waits 2 s after opening the port
        for can_id, data in before:
            adapter.frame(can_id, data)
        lost, back = pull_out_and_back(adapter, recorder, spec, away_s=1.0)
        for can_id, data in after:
            adapter.frame(can_id, data)
        adapter.wait_read()
        time.sleep(0.3)
        code = recorder.stop(signal.SIGINT)
    finally:
        adapter.close()
    assert code == 0, "\n".join(recorder.lines)
    assert "Could not read from serial device" in lost
    assert "(gone " in lost or "(gone " in recorder.wait_for("retrying in")
    assert f"opened {spec} (listen-only) again after " in back
    assert recorder.lines[-1].startswith("recorded 629 frames"), recorder.lines[-1]
    assert recorder.lines[-1].endswith("ended: SIGINT")
    noise = [line for line in recorder.lines if not line.startswith(("recording ", "recorded "))]
    assert noise == []  # no driver warnings, no traceback: status lines and the summary
    recording = tmp_path / "flight.mcap"
    frames = [item for item in read_replay(recording) if isinstance(item, CanFrame)]
    assert [(f.can_id, f.data) for f in frames] == before + after
    links = link_states(recording)
    states = [e.fields["state"] for e in links]
    assert states[:3] == ["open", "lost", "reconnecting"]
    assert states[-1] == "open" and "connect_failed" in states
    assert links[-1].fields["down_s"] >= 1.0
    assert links[-1].fields["lost_at"] == links[1].time
    assert_diagnostics_match_their_schema(recording)
    # opened listen-only both times, with the same bitrate; never asked to transmit
    assert adapter.commands.count(b"L") >= 2 and b"O" not in adapter.commands
    assert adapter.commands.count(b"S8") == 2
    assert adapter.transmit_requests == []


class SerialGimbal(PtyDevice):
    """The gimbal's UART behind a USB serial adapter; what the host writes is kept."""

    def __init__(self, link: Path) -> None:
        super().__init__(link)
        self.from_host = b""

    def received(self, data: bytes) -> None:
        self.from_host += data


def test_record_keeps_every_byte_across_an_unplugged_serial_adapter(
    tmp_path: Path, recorders: list[Recorder]
) -> None:
    device = SerialGimbal(tmp_path / "serial" / "by-id" / FTDI)
    device.plug()
    messages = [wrap_control(bytes([0x0F, 0x04, 0x0C, i, 0, 0, 0, 0])) for i in range(60)]
    spec = f"serial:{device.link}@115200"
    recorder = Recorder(tmp_path, "--source", spec, "-o", "uart.mcap")
    recorders.append(recorder)
    try:
        recorder.wait_for("opened ")
        time.sleep(0.3)  # pyserial has set the port up (raw, 115200)
        for message in messages[:30]:
            device.write(message)
        pull_out_and_back(device, recorder, spec)
        time.sleep(0.3)
        for message in messages[30:]:
            device.write(message)
        device.wait_read()
        time.sleep(0.3)
        code = recorder.stop(signal.SIGTERM)
    finally:
        device.close()
    assert code == 0, "\n".join(recorder.lines)
    assert recorder.lines[-1].endswith("ended: SIGTERM")
    recording = tmp_path / "uart.mcap"
    chunks = [item for item in read_replay(recording) if isinstance(item, StreamChunk)]
    assert b"".join(c.data for c in chunks) == b"".join(messages)
    states = [e.fields["state"] for e in link_states(recording)]
    assert states[:3] == ["open", "lost", "reconnecting"] and states[-1] == "open"
    assert device.from_host == b""  # nothing was ever written to the UART


def test_an_adapter_that_never_comes_back_ends_with_duration(
    tmp_path: Path, recorders: list[Recorder]
) -> None:
    device = SerialGimbal(tmp_path / "serial" / "by-id" / FTDI)
    device.plug()
    spec = f"serial:{device.link}@115200"
    recorder = Recorder(tmp_path, "--source", spec, "-o", "uart.mcap", "--duration", "3")
    recorders.append(recorder)
    try:
        recorder.wait_for("opened ")
        time.sleep(0.3)
        device.write(wrap_control(bytes(8)))
        device.wait_read()
        device.unplug()  # and never plugged in again
        code = recorder.proc.wait(DEADLINE_S)
        recorder._reader.join(DEADLINE_S)
    finally:
        device.close()
    assert code == 0, "\n".join(recorder.lines)
    assert recorder.lines[-2].endswith("ended: stopped")
    assert recorder.lines[-1].startswith(
        f"gimbal-analyzer record: warning: {spec} had not come back when the capture ended "
        f"(cannot open {spec}: No such file or directory (gone "
    )
    assert any(" lost: " in line and "(gone " in line for line in recorder.lines)
    chunks = [i for i in read_replay(tmp_path / "uart.mcap") if isinstance(i, StreamChunk)]
    assert b"".join(c.data for c in chunks) == wrap_control(bytes(8))


def test_an_adapter_that_is_not_there_fails_at_start(tmp_path: Path) -> None:
    link = tmp_path / "serial" / "by-id" / CANABLE
    for spec in (f"can:slcan:{link}@1000000", f"serial:{link}@115200"):
        proc = subprocess.run(
            [sys.executable, "-m", "analyzer", "record", "--source", spec, "-o", "x.mcap"],
            cwd=tmp_path,
            env={**os.environ, "PYTHONPATH": str(ROOT)},
            capture_output=True,
            text=True,
            timeout=60,
            encoding="utf-8",
        )
        assert proc.returncode == 1, proc.stderr
        lines = proc.stderr.splitlines()
        assert len(lines) == 1 and lines[0].startswith(
            f"gimbal-analyzer record: error: cannot open {spec}: "
        )
        assert "No such file or directory" in lines[0]
        assert not (tmp_path / "x.mcap").exists()


def test_the_camera_video_goes_on_while_the_adapter_is_away(
    rtsp_camera: Any, tmp_path: Path, recorders: list[Recorder]
) -> None:
    device = SerialGimbal(tmp_path / "serial" / "by-id" / FTDI)
    device.plug()
    spec = f"serial:{device.link}@115200"
    camera = ["--video", "main", "--camera", f"127.0.0.1:{rtsp_camera.port}"]
    recorder = Recorder(tmp_path, "--source", spec, "-o", "flight.mcap", *camera)
    recorders.append(recorder)
    try:
        recorder.wait_for("opened ")
        time.sleep(1.0)
        device.write(wrap_control(bytes(8)))
        pull_out_and_back(device, recorder, spec, away_s=1.5)
        time.sleep(0.3)
        device.write(wrap_control(bytes(8)))
        device.wait_read()
        time.sleep(1.0)
        code = recorder.stop(signal.SIGINT)
    finally:
        device.close()
    assert code == 0, "\n".join(recorder.lines)
    recording = tmp_path / "flight.mcap"
    links = link_states(recording)
    lost = next(e.time for e in links if e.fields["state"] == "lost")
    back = [e.time for e in links if e.fields.get("down_s") is not None][-1]
    assert back - lost > 2.0
    video = [
        message.log_time / 1e9
        for _, channel, message in make_reader(recording.open("rb")).iter_messages()
        if channel.topic == "/camera/main"
    ]
    # the camera kept being recorded while the adapter was away: at least 25 fps
    assert sum(lost < t < back for t in video) >= 25 * (back - lost) * 0.8
    assert examine(recording).errors == []
