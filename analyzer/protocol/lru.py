"""A bounded table of per-source decoder state: the least recently used entry goes first."""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Iterator
from typing import Generic, TypeVar

K = TypeVar("K")
V = TypeVar("V")

# Distinct CAN channels / stream sources whose state the decoder keeps at once. A real
# capture has a handful; a hostile or broken file can name millions.
MAX_SOURCES = 1024


class LruTable(Generic[K, V]):
    """``get`` marks an entry as used; ``add`` beyond ``limit`` entries hands the least
    recently used one to ``evict`` (which reports whatever it still held) and drops it."""

    def __init__(self, evict: Callable[[K, V], None], limit: int = MAX_SOURCES) -> None:
        if limit < 1:
            raise ValueError("limit must be at least 1")
        self.limit = limit
        self.evicted = 0
        self._evict = evict
        self._entries: OrderedDict[K, V] = OrderedDict()

    def get(self, key: K) -> V | None:
        entry = self._entries.get(key)
        if entry is not None:
            self._entries.move_to_end(key)
        return entry

    def add(self, key: K, value: V) -> V:
        entries = self._entries
        entries[key] = value
        while len(entries) > self.limit:
            old_key, old_value = entries.popitem(last=False)
            self.evicted += 1
            self._evict(old_key, old_value)
        return value

    def values(self) -> Iterator[V]:
        return iter(list(self._entries.values()))

    def __len__(self) -> int:
        return len(self._entries)
