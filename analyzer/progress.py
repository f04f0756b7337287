"""The progress line of long file work: how far through the input, and the rate, on stderr."""

from __future__ import annotations

import contextlib
import os
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import IO, Protocol

from analyzer.ansi import ansi_ok

PROGRESS_INTERVAL_S = 0.2  # redrawn at most this often
BAR = 30


class Sized(Protocol):
    """What the line needs of a file reader (``analyzer.inputs.base.InputReader``)."""

    source: str
    size_bytes: int | None
    position_bytes: int


@dataclass
class FileRead:
    """A read of a file that no input reader does (a further pass over a recording)."""

    source: str
    size_bytes: int | None
    position_bytes: int = 0


class Progress:
    """One line on stderr, redrawn in place: the input's name, a bar, the share and MB
    read, MB/s and items (frames, chunks) per second. ``run_items`` draws it after each
    batch and clears it at the end, for every command that reads a file."""

    def __init__(self, reader: Sized, stream: IO[str], label: str = "") -> None:
        self.reader = reader
        self.stream = stream
        self.label = label
        self.started = time.monotonic()
        self.last_draw = 0.0
        self.drawn = False
        # Erase to the end of the line where escapes work, else blanks over the last line.
        self.erase = ansi_ok(stream)
        self.width = 0

    @classmethod
    def maybe(
        cls,
        reader: object,
        err: IO[str],
        out: IO[str] | None = None,
        quiet_output: bool = True,
        *,
        quiet: bool = False,
        label: str = "",
    ) -> Progress | None:
        """A progress line, or None: with ``quiet`` (-q), for input of unknown size (standard
        input), when stderr is not a terminal, or when ``out`` is the same terminal and the
        command prints there as it goes (``quiet_output`` False: its lines show progress)."""
        size = getattr(reader, "size_bytes", None)
        if quiet or not isinstance(size, int) or size <= 0 or not isatty(err):
            return None
        if out is not None and isatty(out) and not quiet_output:
            return None
        return cls(reader, err, label)  # type: ignore[arg-type]

    def update(self, items: int | None = None) -> None:
        """Redraw (at most every PROGRESS_INTERVAL_S); ``items`` read so far, if known."""
        now = time.monotonic()
        if now - self.last_draw < PROGRESS_INTERVAL_S:
            return
        self.last_draw = now
        size = self.reader.size_bytes or 1
        done = max(0, min(self.reader.position_bytes, size))
        fraction = done / size
        filled = int(fraction * BAR)
        elapsed = max(now - self.started, 1e-6)
        text = (
            f"{self.label}{self.reader.source[:30]} [{'#' * filled}{'.' * (BAR - filled)}] "
            f"{fraction * 100:5.1f}%  {done / 1e6:.1f}/{size / 1e6:.1f} MB  "
            f"{done / elapsed / 1e6:.1f} MB/s"
        )
        if items is not None:
            text += f"  {items / elapsed:,.0f} frames/s"
        self.stream.write("\r" + self._over(text))
        self.stream.flush()
        self.drawn = True

    def read(self, position: int) -> None:
        """A further pass (``FileRead``) got through ``position`` bytes: redraw."""
        self.reader.position_bytes = position
        self.update()

    def clear(self) -> None:
        if self.drawn:
            self.stream.write("\r" + self._over("") + ("" if self.erase else "\r"))
            self.stream.flush()
            self.drawn = False

    def _over(self, text: str) -> str:
        """``text`` written over the line drawn before: erased to its end, or padded."""
        if self.erase:
            return text + "\033[K"
        padded = text.ljust(self.width)
        self.width = len(text)
        return padded


def isatty(stream: IO[str] | None) -> bool:
    try:
        return stream is not None and bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


@contextlib.contextmanager
def further_pass(
    path: str, err: IO[str], *, quiet: bool = False, label: str = ""
) -> Iterator[Callable[[int], None] | None]:
    """The progress line of a further read of the file ``path`` (a second pass over a
    recording): gives what to tell the bytes read so far, or None when no line shows
    (as ``Progress.maybe``); the line is cleared at the end."""
    try:
        size: int | None = os.path.getsize(path)
    except OSError:
        size = None
    progress = Progress.maybe(FileRead(path, size), err, quiet=quiet, label=label)
    try:
        yield None if progress is None else progress.read
    finally:
        if progress is not None:
            progress.clear()
