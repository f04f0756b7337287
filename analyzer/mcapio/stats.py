"""Counts gathered from events: diagnostics by kind and gaps in the gimbal attitude feedback."""

from __future__ import annotations

import json
from collections import Counter
from dataclasses import dataclass, field

from analyzer.protocol.types import TOPIC_DIAGNOSTICS, TOPIC_GIMBAL_ATTITUDE

# Attitude feedback comes every 500 ms; a gap this long means messages were lost.
GAP_THRESHOLD_S = 1.0


@dataclass
class EventStats:
    """Diagnostics by kind and attitude-feedback gaps, updated one event at a time."""

    diagnostics: Counter[str] = field(default_factory=Counter)
    attitude_count: int = 0
    first_attitude: float | None = None
    last_attitude: float | None = None
    max_gap_s: float = 0.0
    max_gap_at: float | None = None  # time of the attitude message before the longest gap
    gaps_over_threshold: int = 0

    def add(self, topic: str, time: float, kind: str | None = None) -> None:
        if topic == TOPIC_DIAGNOSTICS:
            self.diagnostics[kind or "unknown"] += 1
        elif topic == TOPIC_GIMBAL_ATTITUDE:
            self.attitude(time)

    def attitude(self, time: float) -> None:
        self.attitude_count += 1
        if self.last_attitude is None:
            self.first_attitude = time
        else:
            gap = time - self.last_attitude
            if gap > self.max_gap_s:
                self.max_gap_s = gap
                self.max_gap_at = self.last_attitude
            if gap > GAP_THRESHOLD_S:
                self.gaps_over_threshold += 1
        self.last_attitude = time

    def to_metadata(self) -> dict[str, str]:
        """As an MCAP metadata record (string values only)."""
        return {
            "diagnostics_by_kind": json.dumps(dict(sorted(self.diagnostics.items()))),
            "attitude_count": str(self.attitude_count),
            "first_attitude": "" if self.first_attitude is None else repr(self.first_attitude),
            "last_attitude": "" if self.last_attitude is None else repr(self.last_attitude),
            "feedback_max_gap_s": repr(self.max_gap_s),
            "feedback_max_gap_at": "" if self.max_gap_at is None else repr(self.max_gap_at),
            "feedback_gap_threshold_s": repr(GAP_THRESHOLD_S),
            "feedback_gaps_over_threshold": str(self.gaps_over_threshold),
        }

    @classmethod
    def from_metadata(cls, data: dict[str, str]) -> EventStats:
        """Inverse of to_metadata; raises ValueError / KeyError on a malformed record."""

        def opt(key: str) -> float | None:
            text = data.get(key, "")
            return float(text) if text else None

        kinds = json.loads(data["diagnostics_by_kind"])
        return cls(
            diagnostics=Counter({str(k): int(v) for k, v in kinds.items()}),
            attitude_count=int(data["attitude_count"]),
            first_attitude=opt("first_attitude"),
            last_attitude=opt("last_attitude"),
            max_gap_s=float(data["feedback_max_gap_s"]),
            max_gap_at=opt("feedback_max_gap_at"),
            gaps_over_threshold=int(data["feedback_gaps_over_threshold"]),
        )
