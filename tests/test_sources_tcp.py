"""TCP client and TCP proxy sources against fake IDU / ground station servers on loopback."""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Callable
from typing import Any

import pytest

from analyzer.errors import SourceError
from analyzer.protocol.framing import wrap_control
from analyzer.protocol.types import FROM_IDU, LINK, TO_IDU, Event, StreamChunk
from analyzer.sources import open_source
from analyzer.sources.spec import ProxySpec
from analyzer.sources.tcp_client import TcpClientSource
from analyzer.sources.tcp_proxy import TcpProxySource

DEADLINE_S = 5.0
CONTROL = wrap_control(bytes([0x0F, 0x04, 0x0C, 0xFE, 0, 0, 0, 0]))
FEEDBACK = bytes(range(32))


def read_until(source: Any, done: Callable[[list[Any]], bool]) -> list[Any]:
    items: list[Any] = []
    deadline = time.monotonic() + DEADLINE_S
    while not done(items):
        assert time.monotonic() < deadline, f"timed out; got {items!r}"
        items.extend(source.read(0.05))
    return items


def links(items: list[Any]) -> list[Event]:
    return [i for i in items if isinstance(i, Event) and i.fields.get("kind") == LINK]


def states(items: list[Any]) -> list[str]:
    return [e.fields["state"] for e in links(items)]


def data_of(items: list[Any], direction: str) -> bytes:
    return b"".join(
        i.data for i in items if isinstance(i, StreamChunk) and i.direction == direction
    )


def listener() -> socket.socket:
    server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    server.bind(("127.0.0.1", 0))
    server.listen(4)
    server.settimeout(DEADLINE_S)
    return server


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
        return port


# -- TCP client ----------------------------------------------------------------------------------


def test_client_reconnects_after_the_idu_drops_the_link() -> None:
    server = listener()
    port = server.getsockname()[1]
    release = threading.Event()

    def fake_idu() -> None:
        first, _ = server.accept()
        first.sendall(CONTROL[:10])
        first.sendall(CONTROL[10:])
        time.sleep(0.05)
        first.close()  # the link drops once
        second, _ = server.accept()
        second.sendall(FEEDBACK)
        release.wait(DEADLINE_S)
        second.close()

    thread = threading.Thread(target=fake_idu, daemon=True)
    thread.start()
    source = TcpClientSource("127.0.0.1", port, backoff_initial=0.05, backoff_max=0.2)
    try:
        items = read_until(
            source,
            lambda got: (
                data_of(got, FROM_IDU) == CONTROL + FEEDBACK and states(got).count("connected") == 2
            ),
        )
    finally:
        release.set()
        source.close()
        server.close()
    assert states(items) == ["connected", "lost", "reconnecting", "connected"]
    details = [e.fields["detail"] for e in links(items)]
    assert details[0] == f"connected to 127.0.0.1:{port}"
    assert details[1].startswith("connection lost: ")
    assert details[2] == "reconnecting in 0.1 s"  # 0.05 s, shown to one decimal
    assert source.connections == 2
    chunks = [i for i in items if isinstance(i, StreamChunk)]
    assert all(c.source == "tcp" and c.direction == FROM_IDU for c in chunks)
    assert all(abs(c.time - time.time()) < 60 for c in chunks)
    assert source.description == f"tcp:127.0.0.1:{port}"


def test_client_backs_off_exponentially_up_to_the_cap() -> None:
    port = free_port()  # nobody listens there
    source = TcpClientSource("127.0.0.1", port, backoff_initial=0.01, backoff_max=0.04)
    try:
        items = read_until(source, lambda got: states(got).count("reconnecting") >= 5)
    finally:
        source.close()
    delays = [e.fields["retry_in_s"] for e in links(items) if e.fields["state"] == "reconnecting"]
    assert delays[:5] == [0.01, 0.02, 0.04, 0.04, 0.04]
    assert "connect_failed" in states(items)
    failed = next(e for e in links(items) if e.fields["state"] == "connect_failed")
    assert failed.fields["detail"].startswith(f"cannot connect to 127.0.0.1:{port}: ")


def test_client_never_sends() -> None:
    server = listener()
    received: list[bytes] = []
    done = threading.Event()

    def fake_idu() -> None:
        conn, _ = server.accept()
        conn.sendall(CONTROL)
        conn.settimeout(DEADLINE_S)
        while chunk := conn.recv(100):  # returns b"" when the client closes
            received.append(chunk)
        done.set()

    threading.Thread(target=fake_idu, daemon=True).start()
    source = open_source(f"tcp:127.0.0.1:{server.getsockname()[1]}")
    read_until(source, lambda got: data_of(got, FROM_IDU) == CONTROL)
    source.close()
    assert done.wait(DEADLINE_S)
    server.close()
    assert received == []


def test_client_close_is_prompt_and_idempotent() -> None:
    source = TcpClientSource("127.0.0.1", free_port(), backoff_initial=30.0)
    read_until(source, lambda got: "reconnecting" in states(got))
    started = time.monotonic()
    source.close()
    source.close()
    assert time.monotonic() - started < 2.0


# -- TCP proxy -----------------------------------------------------------------------------------


class FakeIdu:
    """Accepts connections, records what it receives, answers each read with FEEDBACK."""

    def __init__(self) -> None:
        self.server = listener()
        self.port: int = self.server.getsockname()[1]
        self.received: list[bytes] = []
        self.connections = 0
        self._stop = threading.Event()
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self) -> None:
        while not self._stop.is_set():
            try:
                conn, _ = self.server.accept()
            except OSError:
                return
            self.connections += 1
            threading.Thread(target=self._talk, args=(conn,), daemon=True).start()

    def _talk(self, conn: socket.socket) -> None:
        with conn:
            conn.settimeout(DEADLINE_S)
            try:
                while data := conn.recv(4096):
                    self.received.append(data)
                    conn.sendall(FEEDBACK)
            except OSError:
                pass

    def close(self) -> None:
        self._stop.set()
        self.server.close()


def ground_station(port: int) -> socket.socket:
    gs = socket.create_connection(("127.0.0.1", port), timeout=DEADLINE_S)
    return gs


def recv_exactly(sock: socket.socket, size: int) -> bytes:
    out = b""
    while len(out) < size:
        chunk = sock.recv(size - len(out))
        assert chunk, "connection closed early"
        out += chunk
    return out


@pytest.fixture
def idu() -> Any:
    fake = FakeIdu()
    yield fake
    fake.close()


def test_proxy_forwards_unchanged_and_yields_both_directions(idu: FakeIdu) -> None:
    source = open_source(f"proxy:127.0.0.1:0->127.0.0.1:{idu.port}")
    assert isinstance(source, TcpProxySource)
    try:
        gs = ground_station(source.listen_address[1])
        gs.sendall(CONTROL)
        assert recv_exactly(gs, len(FEEDBACK)) == FEEDBACK
        items = read_until(
            source,
            lambda got: data_of(got, TO_IDU) == CONTROL and data_of(got, FROM_IDU) == FEEDBACK,
        )
        assert b"".join(idu.received) == CONTROL
        # the ground station leaves; the next one is accepted and relayed too
        gs.close()
        items += read_until(source, lambda got: "lost" in states(got))
        gs2 = ground_station(source.listen_address[1])
        gs2.sendall(CONTROL + CONTROL)
        assert recv_exactly(gs2, len(FEEDBACK)) == FEEDBACK
        items += read_until(source, lambda got: data_of(got, TO_IDU) == CONTROL + CONTROL)
        gs2.close()
    finally:
        source.close()
    assert b"".join(idu.received) == CONTROL * 3
    assert idu.connections == 2
    chunks = [i for i in items if isinstance(i, StreamChunk)]
    assert {c.source for c in chunks} == {"proxy"}
    assert states(items)[:3] == ["listening", "gs_connected", "connected"]
    assert states(items).count("gs_connected") == 2


def test_proxy_ends_the_pair_when_the_idu_closes() -> None:
    server = listener()

    def rude_idu() -> None:
        conn, _ = server.accept()
        conn.sendall(FEEDBACK)
        conn.close()

    threading.Thread(target=rude_idu, daemon=True).start()
    source = TcpProxySource(ProxySpec("127.0.0.1", 0, "127.0.0.1", server.getsockname()[1]))
    try:
        gs = ground_station(source.listen_address[1])
        assert recv_exactly(gs, len(FEEDBACK)) == FEEDBACK
        assert gs.recv(10) == b""  # the proxy closed the ground station side too
        items = read_until(source, lambda got: "lost" in states(got))
        gs.close()
    finally:
        source.close()
        server.close()
    lost = next(e for e in links(items) if e.fields["state"] == "lost")
    assert "IDU closed the connection" in lost.fields["detail"]


def test_proxy_refuses_a_second_ground_station(idu: FakeIdu) -> None:
    source = TcpProxySource(ProxySpec("127.0.0.1", 0, "127.0.0.1", idu.port))
    try:
        gs = ground_station(source.listen_address[1])
        read_until(source, lambda got: "connected" in states(got))
        intruder = ground_station(source.listen_address[1])
        assert intruder.recv(10) == b""
        items = read_until(source, lambda got: "refused" in states(got))
        gs.sendall(CONTROL)  # the first one still works
        assert recv_exactly(gs, len(FEEDBACK)) == FEEDBACK
        gs.close()
        intruder.close()
    finally:
        source.close()
    assert "refused" in states(items)


def test_proxy_closes_the_ground_station_when_the_idu_is_unreachable() -> None:
    source = TcpProxySource(ProxySpec("127.0.0.1", 0, "127.0.0.1", free_port()))
    try:
        gs = ground_station(source.listen_address[1])
        assert gs.recv(10) == b""
        items = read_until(source, lambda got: "connect_failed" in states(got))
        gs.close()
    finally:
        source.close()
    failed = next(e for e in links(items) if e.fields["state"] == "connect_failed")
    assert failed.fields["detail"].startswith("cannot connect to IDU 127.0.0.1:")


def test_proxy_port_in_use_is_a_source_error() -> None:
    server = listener()
    try:
        with pytest.raises(SourceError, match=r"cannot listen on 127\.0\.0\.1"):
            TcpProxySource(ProxySpec("127.0.0.1", server.getsockname()[1], "127.0.0.1", 9))
    finally:
        server.close()
