"""What Linux, macOS and Windows do differently with files, signals and pipes, in one place."""

from __future__ import annotations

import errno
import os
import signal
import sys

# Added to every os.open of the analyzer: on Windows the C runtime would otherwise write
# each \n byte as \r\n (O_BINARY) and hand the descriptor to child processes
# (O_NOINHERIT); elsewhere O_CLOEXEC keeps it from them.
OPEN_FLAGS = (
    getattr(os, "O_BINARY", 0) | getattr(os, "O_NOINHERIT", 0) | getattr(os, "O_CLOEXEC", 0)
)

# Errors of os.link on file systems without hard links: FAT on a USB stick and some mounts
# (EPERM, ENOTSUP, EOPNOTSUPP, EXDEV, ENOSYS), and FAT / exFAT on Windows (EINVAL).
NO_HARD_LINKS = frozenset(
    {errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EXDEV, errno.ENOSYS, errno.EINVAL}
)

# The signals that end a command as Ctrl-C (SIGINT) does, by name: SIGTERM, and on Windows
# SIGBREAK, which the C runtime raises for Ctrl-Break and when the console window is
# closed (or the user logs off); Windows then allows the process a few seconds to finish.
STOP_SIGNALS: dict[int, str] = {int(signal.SIGTERM): "SIGTERM"}
if hasattr(signal, "SIGBREAK"):
    STOP_SIGNALS[int(signal.SIGBREAK)] = "Ctrl-Break"


def open_fd(path: str | os.PathLike[str], flags: int, mode: int = 0o666) -> int:
    """``os.open`` with ``OPEN_FLAGS``: bytes are written as given on every system."""
    return os.open(path, flags | OPEN_FLAGS, mode)


def set_permissions(fd: int, path: str | os.PathLike[str], mode: int) -> None:
    """The permissions of an open file: through its descriptor where the system can
    (``os.fchmod``; Windows has it from Python 3.13 only), else through its name."""
    fchmod = getattr(os, "fchmod", None)
    if fchmod is not None:
        fchmod(fd, mode)
    else:
        os.chmod(path, mode)


def is_closed_pipe(exc: BaseException) -> bool:
    """Whether a failed write means the reader went away (``| head``): a broken pipe, and
    on Windows EINVAL, which a write to a pipe whose reader closed gives there."""
    if isinstance(exc, BrokenPipeError):
        return True
    return sys.platform == "win32" and isinstance(exc, OSError) and exc.errno == errno.EINVAL
