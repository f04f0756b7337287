"""What the Foxglove SDK says in its log that we show: slow clients and refused handshakes.

The SDK drops messages to a client whose outgoing queue is full without counting them; all
it tells is a log line "outbox for client ADDRESS full", at most once per 30 s for the
whole process. It also logs each client it registers and each handshake it refuses (a
client that does not speak its subprotocol). Its logs are forwarded to Python's logging
here, kept out of the root logger (nothing is printed) and counted.
"""

from __future__ import annotations

import dataclasses
import logging
import threading
import time
from dataclasses import dataclass

SDK_LOGGER = "foxglove"


@dataclass(slots=True)
class SdkReports:
    """Counts of SDK log lines since the process started forwarding them."""

    outbox_full: int = 0  # "outbox for client ... full": messages to a slow client dropped
    last_outbox_full: float = 0.0  # time.time() of the last one
    slow_client: str = ""  # its address
    refused: int = 0  # handshakes refused (wrong subprotocol: older Foxglove versions)
    connected: int = 0  # clients registered
    disconnected: int = 0  # clients unregistered


class _Counter(logging.Handler):
    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.reports = SdkReports()

    def emit(self, record: logging.LogRecord) -> None:
        text = record.getMessage()
        reports = self.reports
        if text.startswith("outbox for client") and text.endswith("full"):
            reports.outbox_full += 1
            reports.last_outbox_full = time.time()
            reports.slow_client = text[len("outbox for client") : -len("full")].strip()
        elif "handshake failed" in text:
            reports.refused += 1
        elif text.startswith("Registered client"):
            reports.connected += 1
        elif text.startswith("Unregistered client"):
            reports.disconnected += 1


_lock = threading.Lock()
_counter: _Counter | None = None


def sdk_reports() -> SdkReports:
    """Start forwarding the SDK's log (once per process, before its first server starts)
    and return a copy of the counts so far."""
    global _counter
    with _lock:
        if _counter is None:
            _counter = _install()
        counter = _counter
    counter.acquire()  # the lock logging holds around emit()
    try:
        return dataclasses.replace(counter.reports)
    finally:
        counter.release()


def _install() -> _Counter:
    import foxglove

    counter = _Counter()
    logger = logging.getLogger(SDK_LOGGER)
    logger.addHandler(counter)
    logger.setLevel(logging.INFO)
    logger.propagate = False  # the SDK's chatter stays off the terminal
    # The SDK calls logging.basicConfig() when the root logger has no handler, which
    # would print every library's log from then on: give it one for the moment.
    root = logging.getLogger()
    placeholder = logging.NullHandler()
    root.addHandler(placeholder)
    try:
        foxglove.set_log_level(logging.INFO)
    finally:
        root.removeHandler(placeholder)
    return counter
