"""Counts gathered from events: diagnostics by kind and gaps in the gimbal attitude feedback."""

from __future__ import annotations

import json
from collections import Counter
from dataclasses import dataclass, field

from analyzer.feedback_track import GAP_THRESHOLD_S, FeedbackTrack
from analyzer.protocol.types import TOPIC_DIAGNOSTICS, TOPIC_GIMBAL_ATTITUDE


@dataclass
class EventStats:
    """Diagnostics by kind and attitude-feedback gaps, updated one event at a time."""

    diagnostics: Counter[str] = field(default_factory=Counter)
    feedback: FeedbackTrack = field(default_factory=FeedbackTrack)

    def add(self, topic: str, time: float, kind: str | None = None) -> None:
        if topic == TOPIC_DIAGNOSTICS:
            self.diagnostics[kind or "unknown"] += 1
        elif topic == TOPIC_GIMBAL_ATTITUDE:
            self.feedback.add(time)

    @property
    def attitude_count(self) -> int:
        return self.feedback.count

    @property
    def max_gap_s(self) -> float:
        return self.feedback.longest_gap

    @property
    def max_gap_at(self) -> float | None:
        """Time of the attitude message before the longest gap."""
        return self.feedback.gap_start

    @property
    def gaps_over_threshold(self) -> int:
        return self.feedback.gaps_over_threshold

    def to_metadata(self) -> dict[str, str]:
        """As an MCAP metadata record (string values only)."""
        return {
            "diagnostics_by_kind": json.dumps(dict(sorted(self.diagnostics.items()))),
            "attitude_count": str(self.attitude_count),
            "first_attitude": "" if self.feedback.first is None else repr(self.feedback.first),
            "last_attitude": "" if self.feedback.last is None else repr(self.feedback.last),
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
        feedback = FeedbackTrack(
            count=int(data["attitude_count"]),
            first=opt("first_attitude"),
            last=opt("last_attitude"),
            longest_gap=float(data["feedback_max_gap_s"]),
            gap_start=opt("feedback_max_gap_at"),
            gaps_over_threshold=int(data["feedback_gaps_over_threshold"]),
        )
        return cls(Counter({str(k): int(v) for k, v in kinds.items()}), feedback)
