"""Timing of the gimbal's feedback messages: count, rate, longest silence, gaps over a limit."""

from __future__ import annotations

from dataclasses import dataclass

# The gimbal answers every 500 ms; a silence longer than this means messages were lost.
GAP_THRESHOLD_S = 1.0


@dataclass
class FeedbackTrack:
    """Feedback messages of one stream, folded one message time at a time."""

    count: int = 0
    first: float | None = None
    last: float | None = None
    longest_gap: float = 0.0
    gap_start: float | None = None  # the message before the longest gap
    gap_end: float | None = None  # the message that ended it
    gaps_over_threshold: int = 0

    def add(self, t: float) -> None:
        if self.last is None:
            self.first = t
        else:
            gap = t - self.last
            if gap > self.longest_gap:
                self.longest_gap, self.gap_start, self.gap_end = gap, self.last, t
            if gap > GAP_THRESHOLD_S:
                self.gaps_over_threshold += 1
        self.count += 1
        self.last = t

    @property
    def rate_hz(self) -> float | None:
        if self.count < 2 or self.first is None or self.last is None:
            return None
        span = self.last - self.first
        return (self.count - 1) / span if span > 0 else None
