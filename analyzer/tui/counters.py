"""The monitor's counters of frames, bytes, events and diagnostics, by kind."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

from analyzer.protocol.types import LINK


@dataclass
class Counters:
    """Counts since start or since the user last cleared them."""

    frames: int = 0
    chunks: int = 0
    bytes: int = 0
    events: int = 0
    warnings: int = 0
    kinds: Counter[str] = field(default_factory=Counter)

    @property
    def errors(self) -> int:
        return sum(n for kind, n in self.kinds.items() if kind != LINK)


def count_items(total: Counters, counters: Counters, frames: int, chunks: int, nbytes: int) -> None:
    """Add frames, stream chunks and bytes to both the totals and the clearable counters."""
    for c in (total, counters):
        c.frames += frames
        c.chunks += chunks
        c.bytes += nbytes
