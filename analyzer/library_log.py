"""What python-can and asammdf log while reading a file or opening a bus, kept as words."""

from __future__ import annotations

import contextlib
import logging
import sys
import threading
from collections.abc import Iterator
from typing import Any

# The loggers of the libraries the readers use: asammdf adds its own stderr handler
# (whose records carry whole tracebacks), python-can's would reach Python's last resort.
LIBRARIES = ("can", "asammdf")
MAX_KEPT = 20  # different messages kept per file (a damaged file repeats itself)


class LibraryLog:
    """The first line of each warning or error the libraries logged while reading."""

    def __init__(self) -> None:
        self.messages: list[str] = []
        self._seen: set[str] = set()
        self.dropped = 0

    def add(self, text: str) -> None:
        if text in self._seen:
            return
        if len(self._seen) < MAX_KEPT:
            self._seen.add(text)
            self.messages.append(text)
        else:
            self.dropped += 1

    def take(self) -> list[str]:
        """The messages collected since the last call."""
        taken, self.messages = self.messages, []
        if self.dropped:
            taken.append(f"{self.dropped} other message(s) of the reading library")
            self.dropped = 0
        return taken


class _Router(logging.Handler):
    """Hands a record to the LibraryLog of the reader running in this thread (one line
    on stderr when none is)."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.current = threading.local()

    def emit(self, record: logging.LogRecord) -> None:
        try:
            lines = record.getMessage().strip().splitlines()
        except Exception:  # a record whose arguments do not format
            lines = [str(record.msg)]
        text = f"{record.name.split('.')[0]}: {lines[0] if lines else record.levelname}"
        target: LibraryLog | None = getattr(self.current, "log", None)
        if target is not None:
            target.add(text)
        else:
            print(text, file=sys.stderr)


class _Quiet:
    """An unraisable-exception hook that passes on all but the libraries' own: an
    object of theirs that failed to open cannot clean up after itself (asammdf's
    ``__del__``), which would print an 'Exception ignored' traceback."""

    def __init__(self, inner: Any) -> None:
        self.inner = inner

    def __call__(self, unraisable: Any) -> None:
        module = getattr(unraisable.object, "__module__", "") or ""
        if module.split(".")[0] not in LIBRARIES:
            self.inner(unraisable)


_ROUTER = _Router()
_routed = False
_lock = threading.Lock()


def _install() -> None:
    """Route the libraries' records (once per process) and quiet their cleanup errors
    (again whenever someone replaced the hook)."""
    global _routed
    with _lock:
        if not _routed:
            for name in LIBRARIES:
                logger = logging.getLogger(name)
                logger.handlers = [_ROUTER]
                logger.propagate = False
            _routed = True
        if not isinstance(sys.unraisablehook, _Quiet):
            sys.unraisablehook = _Quiet(sys.unraisablehook)


@contextlib.contextmanager
def library_log(log: LibraryLog) -> Iterator[None]:
    """Inside the block, what the libraries log in this thread goes to ``log``."""
    _install()
    previous = getattr(_ROUTER.current, "log", None)
    _ROUTER.current.log = log
    try:
        yield
    finally:
        _ROUTER.current.log = previous
