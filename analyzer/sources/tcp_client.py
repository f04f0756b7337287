"""TCP client to the IDU's port: reconnects with capped exponential backoff, reports link state."""

from __future__ import annotations

import socket
import threading

from analyzer import wall_clock
from analyzer.protocol.types import FROM_IDU, StreamChunk
from analyzer.sources.netutil import address, close_quietly, enable_keepalive, error_text
from analyzer.sources.reconnect import Put, ReconnectingSource

RECV_SIZE = 65536


class TcpLink:
    """One TCP connection to the IDU at a time; nothing is ever sent on it."""

    open_state = "connected"

    def __init__(self, host: str, port: int, source_name: str, connect_timeout: float) -> None:
        self.host = host
        self.port = port
        self.address = address(host, port)
        self.description = f"tcp:{self.address}"
        self.source_name = source_name
        self.connect_timeout = connect_timeout
        self._sock: socket.socket | None = None

    def open(self) -> None:
        try:
            self._sock = socket.create_connection((self.host, self.port), self.connect_timeout)
        except OSError as exc:
            raise ConnectionError(error_text(exc)) from None

    def receive(self, put: Put, stopping: threading.Event) -> tuple[bool, str]:
        sock = self._sock
        if sock is None:
            return False, "not connected"
        enable_keepalive(sock)
        sock.settimeout(0.25)
        got_data = False
        while not stopping.is_set():
            try:
                data = sock.recv(RECV_SIZE)
            except TimeoutError:
                continue
            except OSError as exc:
                return got_data, error_text(exc)
            if not data:
                return got_data, "closed by the peer"
            got_data = True
            put(StreamChunk(wall_clock.now(), data, self.source_name, FROM_IDU))
        return got_data, "capture stopped"

    def release(self) -> None:
        sock, self._sock = self._sock, None
        close_quietly(sock)

    def interrupt(self) -> None:
        close_quietly(self._sock)

    def opened_words(self) -> str:
        return f"connected to {self.address}"

    def cannot_open_words(self, reason: str) -> str:
        return f"cannot connect to {self.address}: {reason}"

    def lost_words(self, reason: str) -> str:
        return f"connection lost: {reason}"


class TcpClientSource(ReconnectingSource):
    """Connects to the IDU and yields what it sends as StreamChunk(direction=FROM_IDU).

    Nothing is ever sent to the IDU. When the link drops (or cannot be made) it retries
    after ``backoff_initial`` seconds, doubling up to ``backoff_max`` (the loop of
    ``analyzer.sources.reconnect``, shared with CAN and serial sources). Every state
    change is a ``link`` diagnostic ("connected to ...", "connection lost: ...",
    "reconnecting in 2.0 s"), each with ``peer``.
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
        link = TcpLink(host, port, source_name, connect_timeout)
        self.host = host
        self.port = port
        self.address = link.address
        super().__init__(
            link,
            source_name=source_name,
            open_now=False,
            backoff_initial=backoff_initial,
            backoff_max=backoff_max,
            link_fields={"peer": link.address},
        )
