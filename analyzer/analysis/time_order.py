"""Findings put in time order as they are made: each held only until no earlier one can come."""

from __future__ import annotations

import heapq
from typing import Generic, TypeVar

T = TypeVar("T")


class TimeOrder(Generic[T]):
    """Items pushed with a time, released sorted by time (equal times in the order pushed).

    ``release(horizon)`` hands on the items at or before ``horizon``, the earliest time an
    item still to come can carry (``ResponseAnalyzer.earliest_pending``); so what is held
    is what the pending judgements span, not the whole input.
    """

    def __init__(self) -> None:
        self._heap: list[tuple[float, int, T]] = []
        self._pushed = 0

    def __len__(self) -> int:
        return len(self._heap)

    def push(self, time: float, item: T) -> None:
        heapq.heappush(self._heap, (time, self._pushed, item))
        self._pushed += 1

    def release(self, horizon: float | None) -> list[T]:
        """The items with a time at or before ``horizon``, oldest first (none for None)."""
        heap, out = self._heap, []
        while heap and horizon is not None and heap[0][0] <= horizon:
            out.append(heapq.heappop(heap)[2])
        return out

    def drain(self) -> list[T]:
        """Everything still held, oldest first."""
        heap = self._heap
        return [heapq.heappop(heap)[2] for _ in range(len(heap))]

    def clear(self) -> None:
        self._heap.clear()
