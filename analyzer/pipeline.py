"""The hand-over between capture and sinks: batches of raw items with their decoded events."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

from analyzer.protocol.types import CanFrame, Event, StreamChunk

RawItem = CanFrame | StreamChunk


@dataclass(slots=True)
class Batch:
    """Everything one capture step produced, in arrival order.

    ``items`` are the raw frames / stream chunks as read (lossless), ``events`` the
    decoded events and diagnostics they gave (link-state diagnostics included).
    """

    items: list[RawItem] = field(default_factory=list)
    events: list[Event] = field(default_factory=list)
    wall_time: float = 0.0


class Sink(Protocol):
    """Anything that consumes batches: MCAP writer, text printer, TUI bridge."""

    def handle(self, batch: Batch) -> None: ...

    def close(self) -> None: ...
