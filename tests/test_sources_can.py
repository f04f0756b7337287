"""CAN source through python-can's virtual interface: frames arrive, nothing is ever sent."""

from __future__ import annotations

import time
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import can
import pytest

from analyzer.errors import SourceError, UsageError
from analyzer.protocol.types import LINK, TOPIC_DIAGNOSTICS, CanFrame, Event
from analyzer.sources import can_bus, open_source
from analyzer.sources.can_bus import CanSource, listen_only_kwargs
from analyzer.sources.socketcan_links import socketcan_down
from analyzer.sources.spec import CanSpec

DEADLINE_S = 5.0


@pytest.fixture
def channel() -> str:
    return f"test-{uuid.uuid4().hex[:8]}"


@pytest.fixture
def sender(channel: str) -> Iterator[can.BusABC]:
    bus = can.Bus(interface="virtual", channel=channel)
    yield bus
    bus.shutdown()


def read_frames(source: Any, count: int) -> list[Any]:
    items: list[Any] = []
    deadline = time.monotonic() + DEADLINE_S
    while sum(isinstance(i, CanFrame) for i in items) < count and time.monotonic() < deadline:
        items.extend(source.read(0.05))
    return items


def test_frames_arrive_with_their_fields(channel: str, sender: can.BusABC) -> None:
    source = open_source(f"can:virtual:{channel}")
    try:
        sent = [
            can.Message(arbitration_id=0x00000F01, data=bytes([0x0F, 4, 0x0C, 0xFE, 0, 0, 0, 0])),
            can.Message(arbitration_id=0x123, data=b"\x01\x02", is_extended_id=False),
            can.Message(arbitration_id=0x030F0001, data=bytes(8)),
        ]
        for msg in sent:
            sender.send(msg)
        items = read_frames(source, len(sent))
    finally:
        source.close()
    frames = [i for i in items if isinstance(i, CanFrame)]
    assert [(f.can_id, f.data, f.extended) for f in frames] == [
        (0x00000F01, bytes([0x0F, 4, 0x0C, 0xFE, 0, 0, 0, 0]), True),
        (0x123, b"\x01\x02", False),
        (0x030F0001, bytes(8), True),
    ]
    assert all(f.channel == channel and f.direction == "rx" for f in frames)
    assert all(abs(f.time - time.time()) < 60 for f in frames)
    # the first read announces the opened bus as a link diagnostic
    first = items[0]
    assert isinstance(first, Event) and first.topic == TOPIC_DIAGNOSTICS
    assert first.fields["kind"] == LINK and "receive-only" in first.fields["detail"]


class SpyBus:
    """Wraps a real bus and records every call that could put something on the wire."""

    def __init__(self, bus: can.BusABC) -> None:
        self.bus = bus
        self.sent: list[Any] = []

    def recv(self, timeout: float | None = None) -> can.Message | None:
        return self.bus.recv(timeout)

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        self.sent.append(msg)

    def send_periodic(self, *args: Any, **kwargs: Any) -> None:
        self.sent.append(args)

    def shutdown(self) -> None:
        self.bus.shutdown()


def test_source_never_sends(channel: str, sender: can.BusABC) -> None:
    spy = SpyBus(can.Bus(interface="virtual", channel=channel))
    observer = can.Bus(interface="virtual", channel=channel)
    source = CanSource(CanSpec("virtual", channel, None), open_bus=lambda spec: spy)
    try:
        for i in range(50):
            sender.send(
                can.Message(arbitration_id=0x00000F01, data=bytes([0x0F, 7, 0, 0, 0, 0, 0, i]))
            )
        frames = [i for i in read_frames(source, 50) if isinstance(i, CanFrame)]
        assert len(frames) == 50
    finally:
        source.close()
    assert spy.sent == []
    # Nothing but the 50 test frames ever reached another node on the bus.
    seen = []
    while (msg := observer.recv(0.05)) is not None:
        seen.append(msg)
    observer.shutdown()
    assert len(seen) == 50


def test_open_passes_listen_only_and_no_transmit(monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[dict[str, Any]] = []

    class FakeBus:
        def recv(self, timeout: float | None = None) -> None:
            return None

        def shutdown(self) -> None:
            pass

    def fake_bus(**kwargs: Any) -> FakeBus:
        calls.append(kwargs)
        return FakeBus()

    monkeypatch.setattr(can, "Bus", fake_bus)
    open_source("can:slcan:/dev/ttyACM0@500000").close()
    open_source("can:kvaser:0").close()
    open_source("can:socketcan:can0").close()
    assert calls[0] == {
        "interface": "slcan",
        "channel": "/dev/ttyACM0",
        "bitrate": 500_000,
        "listen_only": True,
        "receive_own_messages": False,
    }
    assert calls[1]["driver_mode"] is False and calls[1]["bitrate"] == 1_000_000
    assert "bitrate" not in calls[2]
    assert not ({"listen_only", "driver_mode", "state", "monitor"} & set(calls[2]))


def test_listen_only_options() -> None:
    assert listen_only_kwargs("pcan") == {"state": can.BusState.PASSIVE}
    assert listen_only_kwargs("vector") == {"listen_only": True}
    assert listen_only_kwargs("virtual") == {}
    assert listen_only_kwargs("socketcan") == {}


def test_a_bus_failing_mid_capture_is_reopened_with_the_same_arguments(
    channel: str, sender: can.BusABC
) -> None:
    class UnpluggedBus:
        def recv(self, timeout: float | None = None) -> None:
            raise can.CanOperationError("Could not read from serial device\nmore detail")

        def shutdown(self) -> None:
            raise can.CanOperationError("Could not write to serial device")

    opened: list[CanSpec] = []

    def open_bus(spec: CanSpec) -> Any:
        opened.append(spec)
        if len(opened) == 1:
            return UnpluggedBus()
        if len(opened) == 2:
            raise can.CanInitializationError("could not open port /dev/ttyACM0")
        return can.Bus(interface="virtual", channel=channel)

    spec = CanSpec("virtual", channel, None)
    source = CanSource(spec, open_bus=open_bus, backoff_initial=0.01, backoff_max=0.02)
    try:
        items = read_until_state(source, "open", 2)
        sender.send(can.Message(arbitration_id=0x00000F01, data=bytes(8)))
        items += read_frames(source, 1)
    finally:
        source.close()
    assert opened == [spec, spec, spec]
    links = [i for i in items if isinstance(i, Event) and i.fields.get("kind") == LINK]
    assert [e.fields["state"] for e in links] == [
        "open",
        "lost",
        "reconnecting",
        "connect_failed",
        "reconnecting",
        "open",
    ]
    details = [e.fields["detail"] for e in links]
    assert details[1] == f"can:virtual:{channel} lost: Could not read from serial device"
    assert details[3] == (f"cannot open can:virtual:{channel}: could not open port /dev/ttyACM0")
    assert details[5].startswith(f"opened can:virtual:{channel} (receive-only) again after ")
    assert links[5].fields["down_s"] >= 0.01
    assert links[5].fields["lost_at"] == links[1].time
    assert links[5].time - links[1].time == pytest.approx(links[5].fields["down_s"], abs=1e-3)
    assert next(i for i in items if isinstance(i, CanFrame)).can_id == 0x00000F01


def test_a_socketcan_interface_that_is_down_is_not_open(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    class Bus:
        closed = 0

        def recv(self, timeout: float | None = None) -> None:
            return None

        def shutdown(self) -> None:
            Bus.closed += 1

    down = {"can0"}
    monkeypatch.setattr(can_bus, "socketcan_down", lambda name: name in down)
    spec = CanSpec("socketcan", "can0", None)
    with pytest.raises(
        SourceError,
        match=r"^cannot open can:socketcan:can0: can0 is down "
        r"\(sudo ip link set can0 up type can bitrate 1000000 listen-only on\)$",
    ):
        CanSource(spec, open_bus=lambda spec: Bus())
    assert Bus.closed == 1
    down.clear()  # ip link set can0 up
    source = CanSource(spec, open_bus=lambda spec: Bus())
    source.close()
    assert Bus.closed == 2


def test_sysfs_says_whether_an_interface_is_down(tmp_path: Path) -> None:
    (tmp_path / "can0").mkdir()
    (tmp_path / "can0" / "flags").write_text("0x80\n", encoding="utf-8")
    (tmp_path / "can1").mkdir()
    (tmp_path / "can1" / "flags").write_text("0x40081\n", encoding="utf-8")
    assert socketcan_down("can0", tmp_path)
    assert not socketcan_down("can1", tmp_path)
    assert not socketcan_down("vcan9", tmp_path)


def read_until_state(source: Any, state: str, count: int) -> list[Any]:
    items: list[Any] = []
    deadline = time.monotonic() + DEADLINE_S
    while sum(isinstance(i, Event) and i.fields.get("state") == state for i in items) < count:
        assert time.monotonic() < deadline, f"timed out; got {items!r}"
        items.extend(source.read(0.05))
    return items


def test_a_bus_that_never_opens_fails_at_start() -> None:
    def open_bus(spec: CanSpec) -> Any:
        raise can.CanInitializationError("could not open port /dev/ttyACM7: No such file")

    with pytest.raises(SourceError, match=r"^cannot open can:slcan:/dev/ttyACM7@1000000: could"):
        CanSource(CanSpec("slcan", "/dev/ttyACM7", 1_000_000), open_bus=open_bus)
    with pytest.raises(UsageError, match="unknown CAN interface 'nosuch'"):
        open_source("can:nosuch:0")


def test_error_frames_are_kept(channel: str, sender: can.BusABC) -> None:
    source = open_source(f"can:virtual:{channel}")
    try:
        sender.send(can.Message(arbitration_id=0, is_error_frame=True, data=bytes(8)))
        frames = [i for i in read_frames(source, 1) if isinstance(i, CanFrame)]
    finally:
        source.close()
    assert frames[0].is_error


def test_socketcan_that_is_not_there_points_to_interfaces() -> None:
    """python-can's own socketcan interface, on a computer without SocketCAN (the OS says
    'Address family not supported') or without can0 ('No such device')."""
    try:
        source = open_source("can:socketcan:can0")
    except SourceError as exc:
        words = str(exc)
    else:
        source.close()
        pytest.skip("this computer has a SocketCAN can0")
    assert words.startswith("cannot open can:socketcan:can0: ")
    assert "`gimbal-analyzer interfaces` lists the adapters this computer has" in words
    if "Address family not supported" in words:
        assert "this computer has no SocketCAN" in words


def test_what_python_can_logs_while_opening_a_bus_is_no_line_on_stderr(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """python-can's pcan module logs 'uptime library not available' when imported: that is
    no line printed before everything else; an opened bus's link event keeps it."""
    import subprocess
    import sys

    record = ["record", "--source", "can:pcan:PCAN_USBBUS1", "-o", "never.mcap", "--duration", "1"]
    done = subprocess.run(
        [sys.executable, "-m", "analyzer", *record],
        capture_output=True,
        text=True,
        encoding="utf-8",
        timeout=60,
        check=False,
        cwd=tmp_path,
    )
    assert done.returncode != 0 and done.stdout == ""
    assert "uptime" not in done.stderr
    assert done.stderr.startswith("gimbal-analyzer record: error: cannot open can:pcan:")
    assert len(done.stderr.splitlines()) == 1
    assert not (tmp_path / "never.mcap").exists()

    class Bus:
        def recv(self, timeout: float | None = None) -> None:
            time.sleep(0.01)

        def shutdown(self) -> None:
            pass

    def open_bus(spec: CanSpec) -> Bus:
        import logging

        logging.getLogger("can.pcan").warning("uptime library not available, timestamps ...")
        return Bus()

    source = CanSource(CanSpec("pcan", "PCAN_USBBUS1", None), open_bus=open_bus)
    try:
        opened = read_until_state(source, "open", 1)
    finally:
        source.close()
    link = next(i for i in opened if isinstance(i, Event) and i.fields.get("state") == "open")
    assert link.fields["detail"] == (
        "opened can:pcan:PCAN_USBBUS1 (listen-only); can: uptime library not available, "
        "timestamps ..."
    )
    assert "uptime" not in capsys.readouterr().err
