"""The sink that hands batches from the capture thread to the UI thread, whole and coalesced."""

from __future__ import annotations

import threading
from collections.abc import Callable

from analyzer.pipeline import Batch

MAX_BACKLOG = 1200  # batches waiting for the UI (about a minute at 20 batches/s)


class TuiBridge:
    """A :class:`~analyzer.pipeline.Sink` for the monitor app.

    ``handle()`` runs in the capture thread: it queues the batch and, only when the
    queue was empty, calls ``notify`` (the app posts itself one message). The UI thread
    then ``take()``s every waiting batch at once, so the number of messages is at most
    the number of batches and drops to one per UI wake-up under load. If the UI stalls
    for longer than ``max_backlog`` batches the oldest are dropped from the display and
    counted (recording sinks get every batch from the capture regardless).
    """

    def __init__(self, max_backlog: int = MAX_BACKLOG) -> None:
        self.max_backlog = max_backlog
        self._lock = threading.Lock()
        self._pending: list[Batch] = []
        self._notify: Callable[[], object] | None = None
        self._notified = False
        self._dropped = 0
        self.closed = False
        self.batches = 0
        self.notifications = 0

    def connect(self, notify: Callable[[], object]) -> None:
        """Called by the app once it runs; batches that came earlier are announced now."""
        with self._lock:
            self._notify = notify
            wake = bool(self._pending or self.closed) and not self._notified
            self._notified = self._notified or wake
        if wake:
            self._wake(notify)

    def disconnect(self) -> None:
        with self._lock:
            self._notify = None

    # -- Sink (capture thread) ---------------------------------------------------------------

    def handle(self, batch: Batch) -> None:
        with self._lock:
            self.batches += 1
            self._pending.append(batch)
            if len(self._pending) > self.max_backlog:
                excess = len(self._pending) - self.max_backlog
                del self._pending[:excess]
                self._dropped += excess
            notify = self._notify if not self._notified else None
            if notify is not None:
                self._notified = True
        if notify is not None:
            self._wake(notify)

    def close(self) -> None:
        with self._lock:
            self.closed = True
            notify = self._notify if not self._notified else None
            if notify is not None:
                self._notified = True
        if notify is not None:
            self._wake(notify)

    # -- UI thread ---------------------------------------------------------------------------

    def take(self) -> tuple[list[Batch], int]:
        """Every waiting batch, oldest first, and how many were dropped since the last call."""
        with self._lock:
            batches, self._pending = self._pending, []
            dropped, self._dropped = self._dropped, 0
            self._notified = False
        return batches, dropped

    @property
    def backlog(self) -> int:
        with self._lock:
            return len(self._pending)

    def _wake(self, notify: Callable[[], object]) -> None:
        self.notifications += 1
        try:
            notify()
        except Exception:
            # the app is shutting down; the next connect() announces what waits
            with self._lock:
                self._notified = False
