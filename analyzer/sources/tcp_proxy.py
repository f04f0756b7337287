"""TCP proxy between ground station and IDU: forwards bytes unchanged, yields both directions."""

from __future__ import annotations

import contextlib
import selectors
import socket
from typing import Any

from analyzer import wall_clock
from analyzer.errors import SourceError
from analyzer.protocol.types import FROM_IDU, TO_IDU, StreamChunk
from analyzer.sources.base import QueuedSource, link_event
from analyzer.sources.netutil import address, close_quietly, enable_keepalive, error_text
from analyzer.sources.spec import ProxySpec

RECV_SIZE = 65536
SEND_TIMEOUT = 5.0


WILDCARD_HOSTS = frozenset({"0.0.0.0", "::", ""})


def listen_note(host: str, port: int, idu: str) -> str:
    """Where the proxy listens, in words: all interfaces is said so, with the address."""
    where = address(host, port)
    if host in WILDCARD_HOSTS:
        return (
            f"listening on all interfaces ({where}) for the ground station: reachable from "
            f"other machines; proxy:127.0.0.1:{port}->{idu} keeps it on this one"
        )
    return f"listening on {where} for the ground station"


class TcpProxySource(QueuedSource):
    """Listens for the ground station, connects to the IDU for it, relays both ways.

    One ground station at a time: a second one is refused (and told so by a closed
    connection) while the first is connected; after it leaves the next is accepted.
    Either side closing ends the pair (the other side is closed too, as a direct link
    would). Bytes are forwarded exactly as received; each read also becomes a
    StreamChunk, ``gs_to_idu`` or ``idu_to_gs``. Link changes are ``link`` diagnostics.
    """

    thread_name = "tcp-proxy"

    def __init__(
        self, spec: ProxySpec, *, source_name: str = "proxy", connect_timeout: float = 3.0
    ) -> None:
        super().__init__()
        self.spec = spec
        self.source_name = source_name
        self.connect_timeout = connect_timeout
        self.idu_address = address(spec.idu_host, spec.idu_port)
        try:
            infos = socket.getaddrinfo(
                spec.listen_host, spec.listen_port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE
            )
            family, kind, proto, _, sockaddr = infos[0]
            listener = socket.socket(family, kind, proto)
            listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            listener.bind(sockaddr)
            listener.listen(4)
        except OSError as exc:
            where = address(spec.listen_host, spec.listen_port)
            raise SourceError(f"cannot listen on {where}: {error_text(exc)}") from exc
        self._listener = listener
        host, port = listener.getsockname()[:2]
        self.listen_address: tuple[str, int] = (host, port)
        self.description = f"proxy:{address(host, port)}->{self.idu_address}"
        self.listen_note = listen_note(host, port, self.idu_address)
        self.sessions = 0
        self._gs: socket.socket | None = None
        self._idu: socket.socket | None = None
        self._start()

    def _link(self, detail: str, state: str, **extra: Any) -> None:
        self._put(link_event(self.source_name, detail, state, **extra))

    def _run(self) -> None:
        selector = selectors.DefaultSelector()
        selector.register(self._listener, selectors.EVENT_READ, "listen")
        self._link(self.listen_note, "listening")
        try:
            while not self._stopping.is_set():
                for key, _ in selector.select(timeout=0.25):
                    if self._stopping.is_set():
                        break
                    if key.data == "listen":
                        self._accept(selector)
                    elif self._gs is not None and self._idu is not None:
                        self._relay(selector, from_gs=key.data == "gs")
        finally:
            self._end_session(selector, None)
            selector.close()
            close_quietly(self._listener)

    def _accept(self, selector: selectors.BaseSelector) -> None:
        try:
            conn, peer = self._listener.accept()
        except OSError:
            return
        who = address(*peer[:2])
        if self._gs is not None:
            close_quietly(conn)
            self._link(f"refused ground station {who}: one is already connected", "refused")
            return
        self._link(f"ground station connected from {who}", "gs_connected", peer=who)
        try:
            idu = socket.create_connection(
                (self.spec.idu_host, self.spec.idu_port), self.connect_timeout
            )
        except OSError as exc:
            close_quietly(conn)
            self._link(
                f"cannot connect to IDU {self.idu_address}: {error_text(exc)};"
                " closed the ground station connection",
                "connect_failed",
                peer=self.idu_address,
            )
            return
        self._link(f"connected to IDU {self.idu_address}", "connected", peer=self.idu_address)
        for sock in (conn, idu):
            enable_keepalive(sock)
            sock.settimeout(SEND_TIMEOUT)
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._gs, self._idu = conn, idu
        self.sessions += 1
        selector.register(conn, selectors.EVENT_READ, "gs")
        selector.register(idu, selectors.EVENT_READ, "idu")

    def _relay(self, selector: selectors.BaseSelector, *, from_gs: bool) -> None:
        src, dst = (self._gs, self._idu) if from_gs else (self._idu, self._gs)
        assert src is not None and dst is not None
        side = "ground station" if from_gs else "IDU"
        try:
            data = src.recv(RECV_SIZE)
        except OSError as exc:
            self._end_session(selector, f"{side} connection lost: {error_text(exc)}")
            return
        if not data:
            self._end_session(selector, f"{side} closed the connection")
            return
        direction = TO_IDU if from_gs else FROM_IDU
        self._put(StreamChunk(wall_clock.now(), data, self.source_name, direction))
        try:
            dst.sendall(data)
        except OSError as exc:
            other = "IDU" if from_gs else "ground station"
            self._end_session(selector, f"cannot forward to {other}: {error_text(exc)}")

    def _end_session(self, selector: selectors.BaseSelector, reason: str | None) -> None:
        for sock in (self._gs, self._idu):
            if sock is not None:
                with contextlib.suppress(KeyError, ValueError):
                    selector.unregister(sock)
                close_quietly(sock)
        had_session = self._gs is not None
        self._gs = self._idu = None
        if reason is not None and had_session:
            self._link(f"connection lost: {reason}; waiting for the ground station", "lost")

    def _shutdown_io(self) -> None:
        # The relay thread notices the stop flag within its select timeout and closes all.
        pass
