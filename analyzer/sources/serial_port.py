"""A UART (pyserial) read passively: bytes in, StreamChunk out, nothing is ever written."""

from __future__ import annotations

import contextlib
import time
from typing import Any

from analyzer.errors import SourceError
from analyzer.protocol.types import StreamChunk
from analyzer.sources.base import QueuedSource, link_event
from analyzer.sources.spec import SerialSpec

POLL_S = 0.1


class SerialSource(QueuedSource):
    """Reads a serial port (any pyserial URL, e.g. ``/dev/ttyUSB0``, ``loop://``).

    An unplugged adapter ends the source with a ``link`` diagnostic and a SourceError.
    """

    thread_name = "serial"

    def __init__(self, spec: SerialSpec, *, source_name: str = "serial", port: Any = None) -> None:
        super().__init__()
        import serial

        self.spec = spec
        self.source_name = source_name
        self.description = f"serial:{spec.url}@{spec.baudrate}"
        try:
            self.port: Any = (
                port
                if port is not None
                else serial.serial_for_url(spec.url, baudrate=spec.baudrate, timeout=POLL_S)
            )
        except (serial.SerialException, ValueError, OSError) as exc:
            raise SourceError(f"cannot open {self.description}: {exc}") from exc
        self._put(link_event(source_name, f"opened {spec.url} at {spec.baudrate} baud", "open"))
        self._start()

    def _run(self) -> None:
        import serial

        while not self._stopping.is_set():
            try:
                waiting = self.port.in_waiting
                data = self.port.read(waiting if waiting > 0 else 1)
            except (serial.SerialException, OSError, TypeError, AttributeError) as exc:
                # TypeError / AttributeError: pyserial's reaction to a port closed under it
                if self._stopping.is_set():
                    return
                message = f"{self.description} failed: {exc}"
                self._put(link_event(self.source_name, message, "lost"))
                self._fail(message)
                return
            if data:
                self._put(StreamChunk(time.time(), bytes(data), self.source_name))

    def close(self) -> None:
        super().close()
        with contextlib.suppress(Exception):
            self.port.close()
