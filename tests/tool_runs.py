"""The tool as a process of its own, the way a user runs it, against a bench gimbal.

``check``, ``replay`` and the bench-check tutorial start ``python -m analyzer`` with
this checkout on the path, read what it printed once it ended, then stop the gimbal
it moved; a run a test did not finish is killed at the fixture's end.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar, TypeVar

ROOT = Path(__file__).resolve().parents[1]
R = TypeVar("R", bound="ToolRun")


def tool_process(
    args: Sequence[str],
    cwd: Path | None = None,
    *,
    stderr: int = subprocess.PIPE,
    **env: str,
) -> subprocess.Popen[str]:
    """``gimbal-analyzer ARGS`` (as ``python -m analyzer``) in ``cwd``, its output in pipes
    (``stderr=subprocess.STDOUT``: both in one), ``env`` added to the environment."""
    return subprocess.Popen(
        [sys.executable, "-m", "analyzer", *args],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=stderr,
        text=True,
        env={**os.environ, "PYTHONPATH": str(ROOT), **env},
        encoding="utf-8",
    )


@dataclass
class ToolRun:
    """A run of the tool as a process (``process``); ``finish`` waits for it (at most
    ``timeout_s``), keeps its exit code and output, then stops the gimbal."""

    process: subprocess.Popen[str]
    code: int | None = None
    out: str = ""
    err: str = ""
    timeout_s: ClassVar[float] = 180.0

    def stop_gimbal(self) -> None:
        """Stop what the run moved, once it ended (each kind of run says how)."""
        raise NotImplementedError

    def finish(self: R) -> R:
        if self.code is None:
            self.out, self.err = self.process.communicate(timeout=self.timeout_s)
            self.code = self.process.returncode
            self.stop_gimbal()
        return self

    def abandon(self) -> None:
        """A run no test finished (a fixture's end, a test that failed): killed, and its
        gimbal stopped."""
        if self.code is None:
            self.process.kill()
            self.process.communicate()
            self.stop_gimbal()
