"""Long file work shows how far it is and how fast it goes, on a terminal only.

Every command that reads a file through the pipeline (``decode``, ``analyze``,
``convert``, ``report``, ``table`` for a file it reads itself) draws the same line on stderr when it is a terminal, clears it
at the end, and stays quiet with -q or when stderr is a pipe or a file.
"""

from __future__ import annotations

import io
import os
import pty
import subprocess
import sys
from pathlib import Path

import pytest

from analyzer.progress import Progress

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "samples" / "flight-candump.log"


def run_on_a_terminal(*args: str, cwd: Path) -> tuple[int, str]:
    """Run the command with stderr on a pseudo-terminal (stdout a pipe); what it drew."""
    main, child = pty.openpty()
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen(
        [sys.executable, "-m", "analyzer", *args],
        stdout=subprocess.DEVNULL,
        stderr=child,
        stdin=subprocess.DEVNULL,
        cwd=cwd,
        env=env,
    )
    os.close(child)
    drawn = b""
    while True:
        try:
            chunk = os.read(main, 4096)
        except OSError:  # the child closed the terminal
            break
        if not chunk:
            break
        drawn += chunk
    os.close(main)
    return proc.wait(timeout=60), drawn.decode(errors="replace")


COMMANDS = {
    "decode": ("decode", str(SAMPLE), "--summary"),
    "analyze": ("analyze", str(SAMPLE)),
    "convert": ("convert", str(SAMPLE), "-o", "out.mcap"),
    "report": ("report", str(SAMPLE), "-o", "out.html"),
    "table": ("table", str(SAMPLE), "-o", "fleet"),
}


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_every_command_draws_the_same_progress_line(name: str, tmp_path: Path) -> None:
    code, drawn = run_on_a_terminal(*COMMANDS[name], cwd=tmp_path)
    assert code == 0, drawn
    assert "flight-candump.log [##############################] 100.0%" in drawn
    assert "MB/s" in drawn and "frames/s" in drawn
    assert "\r\033[K" in drawn  # cleared before the command's own last words


@pytest.mark.parametrize("name", ["analyze", "convert", "report", "table"])
def test_quiet_draws_nothing(name: str, tmp_path: Path) -> None:
    code, drawn = run_on_a_terminal(*COMMANDS[name], "-q", cwd=tmp_path)
    assert code == 0 and "%" not in drawn and "MB/s" not in drawn


class Reader:
    source = "big.log"
    size_bytes = 1000
    position_bytes = 250


class Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_only_on_a_terminal_that_output_does_not_use() -> None:
    assert Progress.maybe(Reader(), io.StringIO()) is None  # stderr a pipe
    assert Progress.maybe(Reader(), Tty(), quiet=True) is None
    assert Progress.maybe(Reader(), Tty(), Tty(), quiet_output=False) is None  # lines show it
    sized = Reader()
    sized.size_bytes = None  # type: ignore[assignment]
    assert Progress.maybe(sized, Tty()) is None  # standard input: no size
    err = Tty()
    progress = Progress.maybe(Reader(), err, label="reading ")
    assert progress is not None
    progress.update(500)
    progress.clear()
    text = err.getvalue()
    assert text.startswith("\rreading big.log [#######.......") and " 25.0%" in text
    assert "frames/s" in text and text.endswith("\r\033[K")
