"""Wall-clock time from a monotonic clock anchored once: as fine on Windows as on Linux."""

from __future__ import annotations

import time
from collections.abc import Callable


class WallClock:
    """Unix seconds that advance with ``monotonic`` from one reading of ``wall``.

    ``time.time()`` ticks in 15.6 ms steps on Windows before Python 3.13, so frames that
    arrive a few milliseconds apart would share a time; and it steps when the system clock
    is set. ``time.perf_counter()`` does neither. Read once, the wall clock gives the
    offset; the times then keep the monotonic clock's resolution and never go back."""

    def __init__(
        self,
        wall: Callable[[], float] = time.time,
        monotonic: Callable[[], float] = time.perf_counter,
    ) -> None:
        self.monotonic = monotonic
        self.offset = wall() - monotonic()

    def __call__(self) -> float:
        return self.offset + self.monotonic()


# The process's clock: every live timestamp (frames, stream chunks, link events) is read
# from it, so they are all on one time line.
now = WallClock()
