"""A UART (pyserial) read passively, reopened when the adapter comes back; nothing is written."""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable
from typing import Protocol

from analyzer import wall_clock
from analyzer.protocol.types import StreamChunk
from analyzer.sources.reconnect import DeviceLink, Put, ReconnectingSource, error_words
from analyzer.sources.spec import SerialSpec

POLL_S = 0.1


class ReadablePort(Protocol):
    """What a capture uses of a pyserial port: read and close, never write."""

    @property
    def in_waiting(self) -> int: ...

    def read(self, size: int = 1) -> bytes: ...

    def close(self) -> None: ...


PortOpener = Callable[[SerialSpec], ReadablePort]


def open_port(spec: SerialSpec) -> ReadablePort:
    """pyserial's port for ``spec`` (any pyserial URL), with a short read timeout."""
    import serial

    port: ReadablePort = serial.serial_for_url(spec.url, baudrate=spec.baudrate, timeout=POLL_S)
    return port


class SerialLink(DeviceLink):
    """One pyserial port at a time: only read, never written (reads return within POLL_S)."""

    def __init__(self, spec: SerialSpec, opener: PortOpener, source_name: str) -> None:
        self.spec = spec
        self.source_name = source_name
        self.opener = opener
        self.description = f"serial:{spec.url}@{spec.baudrate}"
        self.port: ReadablePort | None = None

    def open(self) -> None:
        self.port = self.opener(self.spec)

    def receive(self, put: Put, stopping: threading.Event) -> tuple[bool, str]:
        port = self.port
        if port is None:
            return False, "not open"
        got_data = False
        source = self.source_name
        while not stopping.is_set():
            try:
                waiting = port.in_waiting
                data = port.read(waiting if waiting > 0 else 1)
            except Exception as exc:  # SerialException, OSError; TypeError when closed under it
                return got_data, error_words(exc)
            if data:
                got_data = True
                put(StreamChunk(wall_clock.now(), bytes(data), source))
        return got_data, "capture stopped"

    def release(self) -> None:
        port, self.port = self.port, None
        if port is not None:
            with contextlib.suppress(Exception):
                port.close()

    def opened_words(self) -> str:
        return f"opened {self.spec.url} at {self.spec.baudrate} baud"


class SerialSource(ReconnectingSource):
    """Reads a serial port (any pyserial URL, e.g. ``/dev/ttyUSB0``, ``loop://``).

    A port that cannot be opened at the start is a SourceError; one that fails later
    (USB adapter unplugged) is closed and reopened with the same URL and baud rate and
    the same backoff as ``tcp:`` (``analyzer.sources.reconnect``). ``open_port``
    replaces pyserial's opener (tests).
    """

    thread_name = "serial"

    def __init__(
        self,
        spec: SerialSpec,
        *,
        source_name: str = "serial",
        open_port: PortOpener = open_port,
        backoff_initial: float = 0.5,
        backoff_max: float = 10.0,
    ) -> None:
        link = SerialLink(spec, open_port, source_name)
        self.spec = spec
        self.serial_link = link
        super().__init__(
            link,
            source_name=source_name,
            open_now=True,
            backoff_initial=backoff_initial,
            backoff_max=backoff_max,
        )

    @property
    def port(self) -> ReadablePort | None:
        """The open pyserial port (None while the adapter is away)."""
        return self.serial_link.port
