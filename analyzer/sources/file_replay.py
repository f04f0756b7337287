"""Replays a capture file as a source, as fast as possible or at (a multiple of) recorded speed."""

from __future__ import annotations

import contextlib
import importlib
import os
import time
from collections.abc import Iterator
from typing import Any

from analyzer.errors import SourceError, UsageError
from analyzer.sources.base import MAX_ITEMS_PER_READ, SourceItem

_END = object()


class FileReplaySource:
    """Items of ``analyzer.inputs.open_input(path)``; ends (EOFError) when the file does.

    With ``replay_speed`` (1.0 = recorded speed, 2.0 = twice as fast) items are handed
    out when their recorded time is due, relative to the first item; with None they
    come as fast as they are read. Items keep their recorded timestamps.
    """

    live = False

    def __init__(self, path: str, *, replay_speed: float | None = None) -> None:
        if replay_speed is not None and not replay_speed > 0:
            raise UsageError(f"replay speed must be positive, not {replay_speed}")
        if not os.path.exists(path):
            raise UsageError(f"no such file: {path}")
        try:
            open_input = importlib.import_module("analyzer.inputs").open_input
        except (ImportError, AttributeError) as exc:
            raise SourceError(f"cannot replay {path}: file inputs are not available") from exc
        self.path = path
        self.replay_speed = replay_speed
        speed = "" if replay_speed is None else f" at {replay_speed:g}x"
        self.description = f"file:{path}{speed}"
        self._input: Any = open_input(path)
        self._items: Iterator[SourceItem] = iter(self._input)
        self._held: Any = None
        self._start: tuple[float, float] | None = None  # (first item time, monotonic then)
        self._done = False

    def _next(self) -> Any:
        if self._held is None:
            try:
                self._held = next(self._items)
            except StopIteration:
                self._held = _END
            except (UsageError, SourceError):
                raise
            except Exception as exc:
                raise SourceError(f"cannot read {self.path}: {exc}") from exc
        return self._held

    def read(self, timeout: float) -> list[SourceItem]:
        deadline = time.monotonic() + max(0.0, timeout)
        out: list[SourceItem] = []
        while len(out) < MAX_ITEMS_PER_READ:
            item = self._next()
            if item is _END:
                self._done = True
                break
            if self.replay_speed is not None:
                due = self._due(float(item.time))
                now = time.monotonic()
                if due > deadline:
                    if now < deadline:
                        time.sleep(deadline - now)
                    break
                if due > now:
                    time.sleep(due - now)
            out.append(item)
            self._held = None
        if not out and self._done:
            raise EOFError
        return out

    def _due(self, t: float) -> float:
        if self._start is None:
            self._start = (t, time.monotonic())
        first, wall = self._start
        assert self.replay_speed is not None
        return wall + (t - first) / self.replay_speed

    def close(self) -> None:
        self._done = True
        closer = getattr(self._input, "close", None)
        if callable(closer):
            with contextlib.suppress(Exception):
                closer()
