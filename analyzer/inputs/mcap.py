"""MCAP recordings of this project: their raw CAN frames and stream chunks, for decoding again."""

from __future__ import annotations

import os
from collections.abc import Iterator
from typing import Any

from analyzer.errors import UsageError
from analyzer.inputs.base import InputItem, InputReader, open_binary
from analyzer.protocol.types import INCOMPLETE, diagnostic


class McapReader(InputReader):
    """Raw items of a recording, for decoding again.

    Besides the raw items, ``read_replay`` gives back the diagnostics a new decode cannot
    re-create (link state, bad lines of the original input). A recording whose writer was
    killed is recovered as far as it can be read; a diagnostic then says
    so at the end.
    """

    format_name = "mcap"

    def __init__(self, path: str, *, stored: bool = False) -> None:
        super().__init__(path)
        open_binary(path).close()  # a missing or unreadable file: one-line UsageError
        self.size_bytes = os.path.getsize(path)
        try:
            from analyzer.mcapio.reader import read_events, read_replay
        except ImportError as exc:
            raise UsageError(f"cannot read {path}: MCAP support is not available ({exc})") from None
        # stored: the events as recorded (decoded by the version that wrote the file).
        self._items: Any = read_events(path) if stored else read_replay(path)
        self.stored = stored
        self.items = 0

    def __iter__(self) -> Iterator[InputItem]:
        for item in self._items:
            self.items += 1
            if self.first_time is None:
                self.first_time = item.time
            self.last_time = item.time
            yield item
        self.position_bytes = self.size_bytes or 0
        note = getattr(self._items, "note", "")
        if getattr(self._items, "recovered", False) and note:
            yield diagnostic(self.last_time or 0.0, self.source, INCOMPLETE, note)
        # every damaged part already came as an `incomplete` diagnostic where it was
        for damage in getattr(self._items, "damage", ()):
            self.notes.append(f"{self.path}: damaged recording: {damage.detail}")

    @property
    def stats(self) -> dict[str, int]:
        return {"recorded_events" if self.stored else "items": self.items}
