"""Standard output that fails with one clear error, and a SIGTERM (Windows: Ctrl-Break, the
console closed) that acts like Ctrl-C."""

from __future__ import annotations

import codecs
import contextlib
import errno
import io
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterable, Iterator
from types import FrameType
from typing import Any, TextIO, cast

from analyzer.errors import OutputClosed, OutputError, Terminated
from analyzer.portable import STOP_SIGNALS, is_closed_pipe, open_fd


class GuardedStdout:
    """Wraps standard output: a closed pipe raises ``OutputClosed``, any other write
    failure (``> /dev/full``, a full disk) ``OutputError`` with the reason in words."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream

    def _failed(self, exc: OSError) -> Exception:
        if is_closed_pipe(exc):
            return OutputClosed(errno.EPIPE, exc.strerror)
        return OutputError(f"cannot write to standard output: {exc.strerror or exc}")

    def write(self, text: str) -> int:
        try:
            return self.stream.write(text)
        except OSError as exc:
            raise self._failed(exc) from None

    def writelines(self, lines: Iterable[str]) -> None:
        for line in lines:
            self.write(line)

    def flush(self) -> None:
        try:
            self.stream.flush()
        except OSError as exc:
            raise self._failed(exc) from None

    def isatty(self) -> bool:
        try:
            return bool(self.stream.isatty())
        except (AttributeError, ValueError):
            return False

    def __getattr__(self, name: str) -> Any:
        return getattr(self.stream, name)


def utf8_when_redirected(*streams: TextIO) -> None:
    """Standard output and error sent to a file or a pipe write UTF-8, like every text
    file of the tool (Windows would use its ANSI code page, which has no room for most
    characters); a terminal keeps its own (Windows' console takes any text)."""
    for stream in streams:
        with contextlib.suppress(AttributeError, ValueError, OSError, LookupError):
            if stream.isatty() or codecs.lookup(stream.encoding or "utf-8").name == "utf-8":
                continue
            cast(io.TextIOWrapper, stream).reconfigure(encoding="utf-8")


@contextlib.contextmanager
def guarded_stdout() -> Iterator[GuardedStdout]:
    """``sys.stdout`` is a GuardedStdout inside the block."""
    original = sys.stdout
    guard = GuardedStdout(original)
    sys.stdout = cast(TextIO, guard)
    try:
        yield guard
    finally:
        if sys.stdout is guard:
            sys.stdout = original


def silence_stdout() -> None:
    """Point file descriptor 1 at /dev/null, so the interpreter's last flush of what is
    still buffered cannot fail again after the error was reported."""
    stream = getattr(sys.stdout, "stream", sys.stdout)
    with contextlib.suppress(OSError, ValueError, AttributeError):
        fd = stream.fileno()
        devnull = open_fd(os.devnull, os.O_WRONLY)
        os.dup2(devnull, fd)
        os.close(devnull)


def terminated(signum: int) -> Terminated:
    """The KeyboardInterrupt that a stop signal (``STOP_SIGNALS``) raises, named after it."""
    exc = Terminated()
    exc.signal_name = STOP_SIGNALS.get(signum, Terminated.signal_name)
    return exc


SignalHandler = Callable[[int, FrameType | None], None]


@contextlib.contextmanager
def signals_to(signals: Iterable[int], handler: SignalHandler) -> Iterator[None]:
    """Inside the block ``handler`` takes ``signals``; the handlers before it are back
    after. Only the main thread can set them: in any other the block runs as it is."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {signum: signal.signal(signum, handler) for signum in signals}
    try:
        yield
    finally:
        for signum, before in previous.items():
            signal.signal(signum, before)


@contextlib.contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Inside the block SIGTERM (and Windows' SIGBREAK: Ctrl-Break, the console closed)
    raises ``Terminated`` (a KeyboardInterrupt) in the main thread, so every command
    cleans up after it as after Ctrl-C."""

    def on_stop(signum: int, frame: FrameType | None) -> None:
        raise terminated(signum)

    with signals_to(STOP_SIGNALS, on_stop):
        yield


@contextlib.contextmanager
def interrupts_deferred() -> Iterator[None]:
    """Ctrl-C and the stop signals inside the block take effect when it ends, so a short
    step such as creating an output file and keeping a handle on it is never cut in the
    middle."""
    pending: list[int] = []

    def hold(signum: int, frame: FrameType | None) -> None:
        pending.append(signum)

    with signals_to((int(signal.SIGINT), *STOP_SIGNALS), hold):
        yield
    if pending:
        raise terminated(pending[0]) if pending[0] in STOP_SIGNALS else KeyboardInterrupt


def interrupt_name(exc: BaseException) -> str:
    """``SIGTERM`` (``Ctrl-Break``) for a Terminated, ``Ctrl-C`` for any other
    KeyboardInterrupt."""
    return exc.signal_name if isinstance(exc, Terminated) else "Ctrl-C"
