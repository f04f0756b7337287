"""Retry delays of live links: start small, double after each failure up to a cap."""

from __future__ import annotations


class Backoff:
    """Capped exponential backoff shared by every reconnecting link (``tcp:``, ``can:``,
    ``serial:`` through ``analyzer.sources.reconnect``, and the camera video).

    ``delay`` is the wait before the next attempt; ``failed()`` returns it and doubles
    it (up to ``maximum``) for the attempt after; ``reset()`` starts over, once a
    connection has delivered data.
    """

    __slots__ = ("delay", "initial", "maximum")

    def __init__(self, initial: float = 0.5, maximum: float = 10.0) -> None:
        self.initial = initial
        self.maximum = maximum
        self.delay = initial

    def failed(self) -> float:
        """The wait before the next attempt; the one after waits twice as long."""
        delay = self.delay
        self.delay = min(delay * 2, self.maximum)
        return delay

    def reset(self) -> None:
        self.delay = self.initial
