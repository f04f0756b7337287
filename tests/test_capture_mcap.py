"""End to end: virtual CAN bus and a fake IDU over TCP, through the capture engine, into MCAP."""

from __future__ import annotations

import socket
import threading
import time
import uuid
from pathlib import Path
from typing import Any

import can
import pytest

from analyzer.capture import Capture
from analyzer.protocol.codec import encode_command
from analyzer.protocol.framing import wrap_control
from analyzer.protocol.ids import CONTROL_ID
from analyzer.protocol.types import FROM_IDU, LINK, TOPIC_COMMAND, TOPIC_DIAGNOSTICS, Event
from analyzer.sources import open_source
from analyzer.sources.tcp_client import TcpClientSource

DEADLINE_S = 5.0


def wait_for(condition: Any) -> None:
    deadline = time.monotonic() + DEADLINE_S
    while not condition():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.01)


def mcap_topics(path: Path) -> dict[str, int]:
    from mcap.reader import make_reader

    counts: dict[str, int] = {}
    with path.open("rb") as f:
        reader = make_reader(f, validate_crcs=True)
        for _, channel, _ in reader.iter_messages():
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
    return counts


def test_virtual_bus_recorded_to_mcap(tmp_path: Path) -> None:
    writer = pytest.importorskip("analyzer.mcapio.write.sink")
    channel = f"rec-{uuid.uuid4().hex[:8]}"
    sender = can.Bus(interface="virtual", channel=channel)
    source = open_source(f"can:virtual:{channel}")
    path = tmp_path / "flight.mcap"
    sink = writer.McapSink(path, metadata={"source": source.description})
    capture = Capture(source, [sink])
    capture.start()
    try:
        look_down = encode_command("look_down")
        for i in range(200):
            if i % 10 == 0:
                sender.send(can.Message(arbitration_id=CONTROL_ID, data=look_down))
            else:
                sender.send(can.Message(arbitration_id=0x18FF0000 + i, data=bytes(8)))
        wait_for(lambda: capture.stats.frames == 200)
    finally:
        capture.stop()
        assert capture.join(DEADLINE_S)
        sender.shutdown()
    assert capture.error is None
    counts = mcap_topics(path)
    assert counts["/can/frames"] == 200
    assert counts[TOPIC_COMMAND] == 20
    assert counts[TOPIC_DIAGNOSTICS] >= 1  # the "opened" link notice


def test_tcp_link_drop_is_decoded_and_noted(tmp_path: Path) -> None:
    server = socket.create_server(("127.0.0.1", 0))
    server.settimeout(DEADLINE_S)
    frame = wrap_control(encode_command("specified_angle", yaw_deg=45))
    release = threading.Event()

    def fake_idu() -> None:
        for _ in range(2):
            conn, _ = server.accept()
            conn.sendall(frame)
            if not release.is_set():
                time.sleep(0.05)
                conn.close()
                release.set()
            else:
                time.sleep(0.5)
                conn.close()

    threading.Thread(target=fake_idu, daemon=True).start()
    events: list[Event] = []

    class Collect:
        def handle(self, batch: Any) -> None:
            events.extend(batch.events)

        def close(self) -> None:
            pass

    source = TcpClientSource("127.0.0.1", server.getsockname()[1], backoff_initial=0.05)
    capture = Capture(source, [Collect()])
    capture.start()
    try:
        wait_for(lambda: sum(e.topic == TOPIC_COMMAND for e in events) == 2)
    finally:
        capture.stop()
        capture.join(DEADLINE_S)
        server.close()
    commands = [e for e in events if e.topic == TOPIC_COMMAND]
    assert all(c.fields["yaw_deg"] == 45 and c.fields["direction"] == FROM_IDU for c in commands)
    link = [
        e.fields["state"]
        for e in events
        if e.topic == TOPIC_DIAGNOSTICS and e.fields["kind"] == LINK
    ]
    assert link[:4] == ["connected", "lost", "reconnecting", "connected"]
