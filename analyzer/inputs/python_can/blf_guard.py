"""python-can's BLF reader watched for no progress: an object whose size is 0 is read for ever.

python-can (4.6.1 and earlier; its issues #1581 and #1584) finds the next object of a
container's data with ``data.index(b"LOBJ", pos, pos + 8)`` and moves on by the object's
size. An object whose size field is 0 leaves it where it was: it reads the same object
again, for ever (silently, with a warning each time, or yielding the same frame each
time). Here the container's data notices a search that does not start after the last
one and stops the reading with ``ReadingStalled``, which the reader turns into a
diagnostic.
"""

from __future__ import annotations

import functools
from collections.abc import Iterator
from typing import Any, SupportsIndex


class ReadingStalled(RuntimeError):
    """A library reader went back to where it already was: it would never end.

    Not a ValueError: python-can takes a ValueError of ``data.index`` for the end of a
    container's objects."""


class _WatchedObjects(bytes):
    """A BLF container's data that raises ReadingStalled when python-can looks for an
    object at or before the place where it found the last one."""

    last_start = -1

    def index(
        self,
        sub: Any,
        start: SupportsIndex | None = None,
        end: SupportsIndex | None = None,
    ) -> int:
        if start is not None:
            at = int(start)
            if at <= self.last_start:
                raise ReadingStalled(
                    f"python-can went back to the BLF object at byte {at:,} of a log "
                    "container (an object whose size field is 0): the rest of the file "
                    "cannot be read"
                )
            self.last_start = at
        return super().index(sub, start, end)


@functools.cache
def guarded_blf_reader(base: type[Any]) -> type[Any]:
    """``base`` (python-can's BLFReader) with every container's data watched."""

    class GuardedBLFReader(base):
        def _parse_data(self, data: bytes) -> Iterator[Any]:
            return super()._parse_data(_WatchedObjects(data))

    GuardedBLFReader.__name__ = GuardedBLFReader.__qualname__ = base.__name__
    return GuardedBLFReader
