"""TCP client to the IDU's port: reconnects with capped exponential backoff, reports link state."""

from __future__ import annotations

import socket
import time
from typing import Any

from analyzer.protocol.types import FROM_IDU, StreamChunk
from analyzer.sources.backoff import Backoff
from analyzer.sources.base import QueuedSource, link_event
from analyzer.sources.netutil import address, close_quietly, enable_keepalive, error_text

RECV_SIZE = 65536


class TcpClientSource(QueuedSource):
    """Connects to the IDU and yields what it sends as StreamChunk(direction=FROM_IDU).

    Nothing is ever sent to the IDU. When the link drops (or cannot be made) it retries
    after ``backoff_initial`` seconds, doubling up to ``backoff_max``; the delay starts
    over once a connection has delivered data. Every state change is a ``link``
    diagnostic ("connected to ...", "connection lost: ...", "reconnecting in 2.0 s").
    """

    thread_name = "tcp-client"

    def __init__(
        self,
        host: str,
        port: int,
        *,
        source_name: str = "tcp",
        connect_timeout: float = 3.0,
        backoff_initial: float = 0.5,
        backoff_max: float = 10.0,
    ) -> None:
        super().__init__()
        self.host = host
        self.port = port
        self.address = address(host, port)
        self.description = f"tcp:{self.address}"
        self.source_name = source_name
        self.connect_timeout = connect_timeout
        self.backoff_initial = backoff_initial
        self.backoff_max = backoff_max
        self.connections = 0
        self._sock: socket.socket | None = None
        self._start()

    def _link(self, detail: str, state: str, **extra: Any) -> None:
        self._put(link_event(self.source_name, detail, state, peer=self.address, **extra))

    def _run(self) -> None:
        backoff = Backoff(self.backoff_initial, self.backoff_max)
        while not self._stopping.is_set():
            try:
                sock = socket.create_connection((self.host, self.port), self.connect_timeout)
            except OSError as exc:
                if self._stopping.is_set():
                    break
                self._link(f"cannot connect to {self.address}: {error_text(exc)}", "connect_failed")
            else:
                self._sock = sock
                self.connections += 1
                self._link(f"connected to {self.address}", "connected")
                got_data, reason = self._receive(sock)
                self._sock = None
                close_quietly(sock)
                if self._stopping.is_set():
                    break
                self._link(f"connection lost: {reason}", "lost")
                if got_data:
                    backoff.reset()
            delay = backoff.failed()
            self._link(f"reconnecting in {delay:.1f} s", "reconnecting", retry_in_s=delay)
            if self._stopping.wait(delay):
                break

    def _receive(self, sock: socket.socket) -> tuple[bool, str]:
        enable_keepalive(sock)
        sock.settimeout(0.25)
        got_data = False
        while not self._stopping.is_set():
            try:
                data = sock.recv(RECV_SIZE)
            except TimeoutError:
                continue
            except OSError as exc:
                return got_data, error_text(exc)
            if not data:
                return got_data, "closed by the peer"
            got_data = True
            self._put(StreamChunk(time.time(), data, self.source_name, FROM_IDU))
        return got_data, "capture stopped"

    def _shutdown_io(self) -> None:
        close_quietly(self._sock)
