"""Whether ANSI escapes (colours, erase to the end of the line) work on a stream.

They do on a terminal of Linux and macOS. On Windows they do in a console whose
virtual-terminal mode is on: Windows Terminal turns it on, the older console host shows
``←[36m`` unless the program turns it on, which ``ansi_ok`` does; where it cannot (an old
Windows), the answer is no and the caller writes plain text.
"""

from __future__ import annotations

import sys
from typing import IO, Protocol

ENABLE_VIRTUAL_TERMINAL_PROCESSING = 0x0004


class Console(Protocol):
    """The Windows console calls ``ansi_ok`` needs (tests give a stand-in)."""

    def mode(self, fd: int) -> int | None:
        """The console mode of the console behind ``fd``, None when it is none."""
        ...

    def set_mode(self, fd: int, mode: int) -> bool:
        """Set it; False when the console refuses."""
        ...


class WindowsConsole:
    """``GetConsoleMode`` / ``SetConsoleMode`` of kernel32, through ctypes."""

    def __init__(self) -> None:
        import ctypes
        import msvcrt

        kernel32 = ctypes.WinDLL("kernel32", use_last_error=True)  # type: ignore[attr-defined]
        # HANDLEs are pointer-sized: without argtypes ctypes would pass a C int
        kernel32.GetConsoleMode.argtypes = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_uint32)]
        kernel32.SetConsoleMode.argtypes = [ctypes.c_void_p, ctypes.c_uint32]
        self._kernel32 = kernel32
        self._handle = msvcrt.get_osfhandle  # type: ignore[attr-defined]
        self._dword = ctypes.c_uint32

    def mode(self, fd: int) -> int | None:
        import ctypes

        value = self._dword()
        ok = self._kernel32.GetConsoleMode(self._handle(fd), ctypes.byref(value))
        return int(value.value) if ok else None

    def set_mode(self, fd: int, mode: int) -> bool:
        return bool(self._kernel32.SetConsoleMode(self._handle(fd), mode))


def _isatty(stream: IO[str] | None) -> bool:
    try:
        return stream is not None and bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def ansi_ok(
    stream: IO[str] | None, *, platform: str | None = None, console: Console | None = None
) -> bool:
    """True when ``stream`` is a terminal that shows ANSI escapes (on Windows, once its
    virtual-terminal mode is on: turned on here if it was off)."""
    if not _isatty(stream):
        return False
    if (platform or sys.platform) != "win32":
        return True
    try:
        fd = stream.fileno()  # type: ignore[union-attr]
        console = console if console is not None else WindowsConsole()
    except (AttributeError, ValueError, OSError, ImportError):
        return False
    mode = console.mode(fd)
    if mode is None:
        return False
    if mode & ENABLE_VIRTUAL_TERMINAL_PROCESSING:
        return True
    return console.set_mode(fd, mode | ENABLE_VIRTUAL_TERMINAL_PROCESSING)
