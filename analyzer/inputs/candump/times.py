"""Relative candump screen times: since the start (-tz) or since the previous frame (-td)."""

from __future__ import annotations

import itertools

from analyzer.inputs.base import DELTA, RELATIVE_TO_START
from analyzer.protocol.types import CanFrame

DECIDE_AFTER = 50  # relative times looked at before -tz and -td are told apart by rate


class ScreenTimes:
    """Tells -tz from -td times, which look alike, and puts each frame on the right time.

    Until the lines tell the two apart (a time going back, or most times repeating as a
    steady rate does under -td) the frames are held (``waiting``). ``base`` is the
    decision (or ABSOLUTE, set by the parser for dated times), None while open.
    """

    def __init__(self) -> None:
        self.base: str | None = None
        self._elapsed = 0.0
        self._raw: list[float] = []  # relative times while the base is open
        self._undecided: list[tuple[int, CanFrame]] = []  # held frames and their time index

    @property
    def waiting(self) -> bool:
        return bool(self._undecided)

    def take(self, frame: CanFrame) -> tuple[bool, list[float]]:
        """A frame with a ``(000.123456)`` time: whether its time is final now, and the
        times of the held frames when this frame settled the base (else [])."""
        raw = frame.time
        if self.base == DELTA:
            self._elapsed += raw
            frame.time = self._elapsed
            return True, []
        if self.base is not None:
            return True, []
        self._raw.append(raw)
        self._undecided.append((len(self._raw) - 1, frame))
        times = self._raw
        if len(times) >= 2 and times[-1] < times[-2]:
            return False, self._decide(DELTA)
        if len(times) >= DECIDE_AFTER:
            return False, self._decide(self._steady_guess())
        return False, []

    def settle(self) -> list[float]:
        """The end of the input: decide on what was seen; the held frames' times."""
        if self.base is None and self._raw:
            return self._decide(self._steady_guess())
        return []

    def _steady_guess(self) -> str:
        """No time went back: mostly repeated times mean a steady rate under -td."""
        times = self._raw[1:]
        repeats = sum(1 for a, b in itertools.pairwise(times) if a == b)
        return DELTA if times and repeats * 2 > len(times) else RELATIVE_TO_START

    def _decide(self, base: str) -> list[float]:
        self.base = base
        times = self._raw
        if base == DELTA:
            total, sums = 0.0, []
            for t in times:
                total += t
                sums.append(total)
            self._elapsed = total
            for index, frame in self._undecided:
                frame.time = sums[index]
            times = sums
        self._raw = []
        self._undecided = []
        return times
