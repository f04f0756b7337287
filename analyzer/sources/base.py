"""The Source protocol shared by live inputs, and a queue-fed base for thread-driven sources."""

from __future__ import annotations

import contextlib
import queue
import threading
import time
from typing import Any, Protocol, runtime_checkable

from analyzer.errors import SourceError
from analyzer.protocol.types import LINK, CanFrame, Event, StreamChunk, diagnostic

SourceItem = CanFrame | StreamChunk | Event

# Upper bound of items one ``read`` returns, so one capture batch stays bounded.
MAX_ITEMS_PER_READ = 5000


@runtime_checkable
class Source(Protocol):
    """Anything the capture engine can read from.

    ``read(timeout)`` returns what arrived within ``timeout`` seconds (``[]`` when nothing
    did) and raises ``EOFError`` once a finite source is exhausted, or ``SourceError``
    when it failed for good. ``close()`` releases everything and may be called twice.
    """

    description: str

    def read(self, timeout: float) -> list[SourceItem]: ...

    def close(self) -> None: ...


def link_event(source: str, detail: str, state: str, **extra: Any) -> Event:
    """A /diagnostics event of kind ``link``: a connection state change of a live source."""
    return diagnostic(time.time(), source, LINK, detail, state=state, **extra)


class QueuedSource:
    """Base for sources whose I/O runs in a background thread that fills a queue.

    Subclasses implement ``_run()`` (loop until ``self._stopping`` is set) and put items
    with ``_put``; a fatal error is reported with ``_fail`` and surfaces from ``read``.
    """

    description: str = ""
    thread_name: str = "source"

    def __init__(self) -> None:
        self._queue: queue.SimpleQueue[SourceItem] = queue.SimpleQueue()
        self._stopping = threading.Event()
        self._finished = threading.Event()
        self._error: str | None = None
        self._thread: threading.Thread | None = None

    def _start(self) -> None:
        self._thread = threading.Thread(target=self._main, name=self.thread_name, daemon=True)
        self._thread.start()

    def _main(self) -> None:
        try:
            self._run()
        except Exception as exc:  # a bug or an OS error nobody handled: end with a message
            self._fail(f"{self.description}: {exc.__class__.__name__}: {exc}")
        finally:
            self._finished.set()

    def _run(self) -> None:
        raise NotImplementedError

    def _put(self, item: SourceItem) -> None:
        self._queue.put(item)

    def _fail(self, message: str) -> None:
        if self._error is None:
            self._error = message

    def read(self, timeout: float) -> list[SourceItem]:
        out: list[SourceItem] = []
        with contextlib.suppress(queue.Empty):
            out.append(self._queue.get(timeout=max(0.0, timeout)))
        while len(out) < MAX_ITEMS_PER_READ:
            try:
                out.append(self._queue.get_nowait())
            except queue.Empty:
                break
        if not out and self._finished.is_set():
            if self._error is not None:
                raise SourceError(self._error)
            raise EOFError
        return out

    def close(self) -> None:
        self._stopping.set()
        self._shutdown_io()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=5.0)

    def _shutdown_io(self) -> None:
        """Unblock the I/O thread (close sockets / ports); called from ``close``."""
