"""Rates from the messages' own times over a window: they cannot read 0 while messages come.

Counting what arrived in each second and dividing by the second is exact for a busy bus
and wrong for a slow message: the gimbal's feedback comes every 0.5 s, so a one-second
count is 1, 2 or 3 by where the second's edges fall (1.0, 2.0, 3.0 /s for a steady 2 Hz),
and a message every 1.5 s reads 0 in one second of two. A ``Meter`` keeps the times of
the last ``window`` seconds instead and divides what came after the first of them by the
time from the first to the last: a steady 2 Hz reads 2.0 however the seconds fall. When
the messages stop, the silence beyond one and a half usual intervals is added to that
time, so the rate falls smoothly, and it is 0 once the silence is longer than the window
and than twice the usual interval (a slow message keeps its rate between two of its kind).
"""

from __future__ import annotations

from collections import deque

RATE_WINDOW_S = 5.0  # the messages of the last 5 s make a rate
LATE = 1.5  # a message this many usual intervals after the last is late: the rate falls


class Meter:
    """How much per second arrives, from the times things arrived (``add``)."""

    __slots__ = ("_amounts", "_times", "_total", "window")

    def __init__(self, window: float = RATE_WINDOW_S) -> None:
        self.window = window
        self._times: deque[float] = deque()
        self._amounts: deque[float] = deque()
        self._total = 0.0  # of _amounts

    def add(self, t: float, amount: float = 1.0) -> None:
        """``amount`` (one message, a batch's frames or bits) arrived at ``t``."""
        times = self._times
        if times and t < times[-1] - self.window:  # time went back: a new log, a new axis
            self.clear()
        times.append(t)
        self._amounts.append(amount)
        self._total += amount
        if len(times) > 2 and times[0] < t - 2 * self.window:
            self._forget(t)

    def rate(self, now: float) -> float:
        """Per second at ``now``: what came after the first time kept, over the time from
        it to the last, lengthened by a silence longer than LATE usual intervals."""
        self._forget(now)
        times = self._times
        if len(times) < 2:
            return 0.0
        span = times[-1] - times[0]
        if span <= 0:
            return 0.0
        gap = span / (len(times) - 1)
        silence = now - times[-1]
        if silence > max(self.window, 2 * gap):
            self.clear()
            return 0.0
        return (self._total - self._amounts[0]) / (span + max(0.0, silence - LATE * gap))

    def clear(self) -> None:
        self._times.clear()
        self._amounts.clear()
        self._total = 0.0

    def _forget(self, now: float) -> None:
        """Drop what is older than the window, keeping the last two (a slow message's)."""
        times, amounts = self._times, self._amounts
        start = now - self.window
        while len(times) > 2 and times[0] < start:
            times.popleft()
            self._total -= amounts.popleft()
