"""The Source protocol shared by live inputs, and a queue-fed base for thread-driven sources."""

from __future__ import annotations

import contextlib
import queue
import threading
from typing import Any, Protocol, runtime_checkable

from analyzer import wall_clock
from analyzer.errors import SourceError
from analyzer.protocol.types import LINK, CanFrame, Event, StreamChunk, diagnostic

SourceItem = CanFrame | StreamChunk | Event

# Upper bound of items one ``read`` returns, so one capture batch stays bounded.
MAX_ITEMS_PER_READ = 5000
# What a source's I/O thread may queue ahead of the capture: about 13 s of a saturated
# 1 Mbit/s CAN bus, or 32 MiB of stream bytes. Beyond that new data is dropped, counted
# and reported (as candump does), instead of growing until the machine runs out of memory.
MAX_QUEUED_ITEMS = 100_000
MAX_QUEUED_BYTES = 32 * 1024 * 1024
OVERFLOW = "overflow"  # state of the link diagnostic that reports dropped data


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


def link_event(
    source: str, detail: str, state: str, *, at: float | None = None, **extra: Any
) -> Event:
    """A /diagnostics event of kind ``link``: a connection state change of a live source
    (at time ``at``, now by default)."""
    return diagnostic(
        wall_clock.now() if at is None else at, source, LINK, detail, state=state, **extra
    )


def overflow_event(source: str, items: int, size: int, total: int) -> Event:
    """The /diagnostics event saying that ``items`` frames / chunks were dropped."""
    event = link_event(
        source,
        f"dropped {items:,} frame(s) / chunk(s) ({size:,} bytes): the analyzer fell behind "
        f"the source and its queue was full ({total:,} dropped in all)",
        OVERFLOW,
    )
    event.fields["byte_count"] = size
    return event


class QueuedSource:
    """Base for sources whose I/O runs in a background thread that fills a queue.

    Subclasses implement ``_run()`` (loop until ``self._stopping`` is set) and put items
    with ``_put``; a fatal error is reported with ``_fail`` and surfaces from ``read``.
    The queue holds at most ``max_items`` frames / chunks and ``max_bytes`` bytes: more
    is dropped and counted (``dropped_items``, ``dropped_bytes``), and a link diagnostic
    of state ``overflow`` marks the place in the stream where data is missing. Link
    events are never dropped.
    """

    description: str = ""
    thread_name: str = "source"
    source_name: str = "source"

    def __init__(self, *, max_items: int | None = None, max_bytes: int | None = None) -> None:
        self._queue: queue.SimpleQueue[SourceItem] = queue.SimpleQueue()
        self.max_items = MAX_QUEUED_ITEMS if max_items is None else max_items
        self.max_bytes = MAX_QUEUED_BYTES if max_bytes is None else max_bytes
        self.dropped_items = 0
        self.dropped_bytes = 0
        self._queued_items = 0
        self._queued_bytes = 0
        self._unreported = (0, 0)  # items, bytes dropped since the last overflow event
        self._count_lock = threading.Lock()
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
        if isinstance(item, Event):
            self._queue.put(item)
            return
        size = len(item.data)
        with self._count_lock:
            if self._queued_items >= self.max_items or (
                self._queued_bytes + size > self.max_bytes and self._queued_items
            ):
                self.dropped_items += 1
                self.dropped_bytes += size
                items, dropped = self._unreported
                self._unreported = (items + 1, dropped + size)
                return
            self._queued_items += 1
            self._queued_bytes += size
            report = self._take_unreported()
        if report is not None:
            self._queue.put(report)  # where the gap is: before the first item after it
        self._queue.put(item)

    def _take_unreported(self) -> Event | None:
        """The overflow event for drops not yet reported (call with the lock held)."""
        items, size = self._unreported
        if not items:
            return None
        self._unreported = (0, 0)
        return overflow_event(self.source_name, items, size, self.dropped_items)

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
        taken = [item for item in out if not isinstance(item, Event)]
        with self._count_lock:
            self._queued_items -= len(taken)
            self._queued_bytes -= sum(len(item.data) for item in taken)
            if self._queued_items == 0:  # drained: report drops nothing arrived after
                report = self._take_unreported()
                if report is not None:
                    out.append(report)
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
