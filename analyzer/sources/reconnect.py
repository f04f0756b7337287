"""The one reconnect loop of live links (tcp, can, serial): open, read, lose, back off, reopen."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any, Protocol

from analyzer import wall_clock
from analyzer.errors import SourceError, UsageError
from analyzer.sources.backoff import Backoff
from analyzer.sources.base import QueuedSource, SourceItem, link_event

# link diagnostic states written by the loop
CONNECT_FAILED = "connect_failed"
LOST = "lost"
RECONNECTING = "reconnecting"

Put = Callable[[SourceItem], None]


class LiveLink(Protocol):
    """One live link a ``ReconnectingSource`` opens, reads and opens again.

    ``open`` raises the driver's or the OS's error when it cannot open (a UsageError
    for a spec that can never work);
    ``receive`` reads until the link fails or ``stopping`` is set and returns
    (whether anything arrived, the reason it ended); ``release`` closes what ``open``
    opened (quietly, may be called twice); ``interrupt`` is called from another
    thread on ``close`` to unblock a read that would otherwise wait.
    """

    description: str
    open_state: str  # the link diagnostic state of an opened link ("open", "connected")

    def open(self) -> None: ...

    def receive(self, put: Put, stopping: threading.Event) -> tuple[bool, str]: ...

    def release(self) -> None: ...

    def interrupt(self) -> None: ...

    def opened_words(self) -> str: ...

    def cannot_open_words(self, reason: str) -> str: ...

    def lost_words(self, reason: str) -> str: ...


class DeviceLink:
    """The words of a link to a local device (a CAN adapter, a serial port), whose reads
    return within a short poll: nothing to interrupt from another thread."""

    description: str = ""
    open_state = "open"

    def interrupt(self) -> None:
        """Nothing: the reader's own short poll hears ``close``."""

    def cannot_open_words(self, reason: str) -> str:
        return f"cannot open {self.description}: {reason}"

    def lost_words(self, reason: str) -> str:
        return f"{self.description} lost: {reason}"


def _first_line(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror:
        return f"{exc.strerror}: {exc.filename}" if exc.filename else exc.strerror
    lines = str(exc).strip().splitlines()
    return lines[0].strip() if lines else exc.__class__.__name__


def _root(exc: BaseException) -> BaseException:
    """The error at the bottom of a chain of errors raised while handling one another."""
    seen = {id(exc)}
    while True:
        under = exc.__cause__ or (None if exc.__suppress_context__ else exc.__context__)
        if under is None or id(under) in seen:
            return exc
        seen.add(id(under))
        exc = under


def error_words(exc: BaseException) -> str:
    """A driver error in one line, with the OS / pyserial error under it when there is one.

    python-can says "Could not read from serial device" and keeps the why underneath:
    "Could not read from serial device: Input/output error". Where the message repeats
    the OS error among paths ("could not open port /dev/x: [Errno 2] No such file or
    directory: '/dev/x'"), the OS error alone is clearer.
    """
    top = _first_line(exc)
    root = _root(exc)
    if root is exc:
        return top
    if isinstance(root, OSError) and root.strerror and root.strerror in top:
        return root.strerror
    why = _first_line(root)
    return top if why in top else f"{top}: {why}"


class ReconnectingSource(QueuedSource):
    """A live link read in a thread, opened again with capped exponential backoff.

    With ``open_now`` the link is opened in the constructor and a failure there is a
    ``SourceError`` at once (a source that never opens fails at start); without it the
    first attempt is the loop's (a ``tcp:`` client waits for its IDU). After that
    nothing ends the source but ``close``: a lost link is reopened after
    ``backoff_initial`` seconds, doubling up to ``backoff_max`` (the delay starts over
    once a connection delivered data). Every change is a ``link`` diagnostic: the
    loss (``lost``, with the reason), each failed attempt (``connect_failed``, with its
    reason), each wait (``reconnecting``, ``retry_in_s``) and the link back (the
    link's ``open_state``, with ``down_s``: how long it was gone, and ``lost_at``).
    """

    def __init__(
        self,
        link: LiveLink,
        *,
        source_name: str,
        open_now: bool,
        backoff_initial: float = 0.5,
        backoff_max: float = 10.0,
        link_fields: dict[str, Any] | None = None,
    ) -> None:
        super().__init__()
        self.link = link
        self.description = link.description
        self.source_name = source_name
        self.backoff_initial = backoff_initial
        self.backoff_max = backoff_max
        self.connections = 0
        self._link_fields = dict(link_fields or {})
        self._open = False
        if open_now:
            self._first_open()
        self._start()

    def _first_open(self) -> None:
        """Open at once: a link that cannot be opened at all is a SourceError now."""
        try:
            self.link.open()
        except (SourceError, UsageError):
            self.link.release()
            raise
        except Exception as exc:  # driver and OS errors: one line naming the source
            self.link.release()
            raise SourceError(self.link.cannot_open_words(error_words(exc))) from exc
        self._opened(None)

    def _link(self, detail: str, state: str, at: float | None = None, **extra: Any) -> None:
        fields = {**self._link_fields, **extra}
        self._put(link_event(self.source_name, detail, state, at=at, **fields))

    def _opened(self, lost_at: float | None) -> None:
        self._open = True
        self.connections += 1
        detail = self.link.opened_words()
        if lost_at is None:
            self._link(detail, self.link.open_state)
            return
        now = wall_clock.now()
        down = max(0.0, now - lost_at)
        self._link(
            f"{detail} again after {down:.1f} s without it",
            self.link.open_state,
            at=now,
            down_s=round(down, 3),
            lost_at=lost_at,
        )

    def _attempt(self, lost_at: float | None) -> None:
        try:
            self.link.open()
        except Exception as exc:  # driver, OS and python-can errors all mean "not yet"
            self.link.release()
            if not self._stopping.is_set():
                self._link(self.link.cannot_open_words(error_words(exc)), CONNECT_FAILED)
        else:
            self._opened(lost_at)

    def _run(self) -> None:
        backoff = Backoff(self.backoff_initial, self.backoff_max)
        lost_at: float | None = None
        try:
            while not self._stopping.is_set():
                if not self._open:
                    self._attempt(lost_at)
                if self._open:
                    got_data, reason = self.link.receive(self._put, self._stopping)
                    self.link.release()
                    self._open = False
                    if self._stopping.is_set():
                        break
                    lost_at = wall_clock.now()
                    self._link(self.link.lost_words(reason), LOST, at=lost_at)
                    if got_data:
                        backoff.reset()
                elif self._stopping.is_set():
                    break
                delay = backoff.failed()
                self._link(f"reconnecting in {delay:.1f} s", RECONNECTING, retry_in_s=delay)
                if self._stopping.wait(delay):
                    break
        finally:
            self.link.release()

    def _shutdown_io(self) -> None:
        self.link.interrupt()
