"""Skip markers for what only some systems have, so the suite collects and runs anywhere.

Windows has no pseudo-terminals, sends no POSIX signals to a process (``send_signal``
of SIGINT is refused, SIGTERM and ``os.kill`` end the process at once, pytest too),
makes symbolic links only with developer mode on, and has no SocketCAN; macOS has no
SocketCAN either. Tests that need one of them say so with these markers.
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

import pytest

WINDOWS = sys.platform == "win32"


def _can_symlink() -> bool:
    with tempfile.TemporaryDirectory() as folder:
        try:
            (Path(folder) / "link").symlink_to(folder)
        except (OSError, NotImplementedError):
            return False
    return True


posix_signals = pytest.mark.skipif(
    WINDOWS, reason="POSIX signals to a process (Windows ends it at once instead)"
)
pseudo_terminals = pytest.mark.skipif(
    WINDOWS or not hasattr(os, "openpty"), reason="needs pseudo-terminals"
)
symlinks = pytest.mark.skipif(not _can_symlink(), reason="this system makes no symbolic links")
posix_permissions = pytest.mark.skipif(WINDOWS, reason="POSIX file permissions")
linux = pytest.mark.skipif(sys.platform != "linux", reason="Linux only (SocketCAN, /dev)")
