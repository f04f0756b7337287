"""Findings summarised per command and check: exact counts by verdict, the worst few kept."""

from __future__ import annotations

import heapq
import itertools
from collections import Counter
from dataclasses import dataclass, field
from typing import Any

from analyzer.analysis.findings import FEEDBACK_COMMAND
from analyzer.protocol.response_fields import (
    DEGRADED,
    HEALTHY,
    LOST,
    NOT_OBEYED,
    OBEYED,
    PARTIAL,
    UNKNOWN,
)

EXAMPLES = 12  # findings shown per command and check, the worst first
# The commands' verdicts, and the feedback's health words beside the one they rank with.
RANK = {NOT_OBEYED: 3, LOST: 3, PARTIAL: 2, DEGRADED: 2, UNKNOWN: 1, OBEYED: 0, HEALTHY: 0}
# How far off a finding is, within one verdict: the larger, the worse.
MAGNITUDE_FIELDS = ("error_deg", "gap_s", "moved_deg", "overshoot_deg", "lag_s", "response_s")


def badness(finding: dict[str, Any]) -> tuple[int, float]:
    """Verdict first (not obeyed is worst), then the size of the miss."""
    size = 0.0
    for name in MAGNITUDE_FIELDS:
        value = finding.get(name)
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            size = abs(float(value))
            break
    ratio = finding.get("rate_ratio")
    if size == 0.0 and isinstance(ratio, (int, float)) and not isinstance(ratio, bool):
        size = abs(1.0 - float(ratio))
    return RANK.get(str(finding.get("verdict")), 0), size


def whole_run(finding: dict[str, Any]) -> bool:
    """A finding about the feedback link over a window, not about one command's moment."""
    return str(finding.get("command")) == FEEDBACK_COMMAND


@dataclass
class Group:
    """The findings of one command and one check."""

    command: str
    check: str
    verdicts: Counter[str] = field(default_factory=Counter)
    first: float | None = None
    last: float | None = None
    # A heap of (badness, -order, finding): the root is the mildest kept example.
    _worst: list[tuple[tuple[int, float], int, dict[str, Any]]] = field(default_factory=list)

    def add(self, finding: dict[str, Any], order: int, keep: int) -> None:
        self.verdicts[str(finding.get("verdict"))] += 1
        t = float(finding.get("time", 0.0))
        self.first = t if self.first is None else min(self.first, t)
        self.last = t if self.last is None else max(self.last, t)
        entry = (badness(finding), -order, finding)  # earlier wins a tie
        if len(self._worst) < keep:
            heapq.heappush(self._worst, entry)
        elif entry[:2] > self._worst[0][:2]:
            heapq.heapreplace(self._worst, entry)

    @property
    def total(self) -> int:
        return sum(self.verdicts.values())

    def examples(self) -> list[dict[str, Any]]:
        """The kept findings, the worst first."""
        return [f for _, _, f in sorted(self._worst, key=lambda e: (e[0], e[1]), reverse=True)]

    def worst_rank(self) -> int:
        return max((RANK.get(v, 0) for v, n in self.verdicts.items() if n), default=0)


class FindingGroups:
    """Every finding counted by (command, check) and verdict; ``keep`` examples per group."""

    def __init__(self, keep: int = EXAMPLES) -> None:
        self.keep = keep
        self.groups: dict[tuple[str, str], Group] = {}
        self.verdicts: Counter[str] = Counter()
        self._order = itertools.count()

    def add(self, finding: dict[str, Any]) -> None:
        key = (str(finding.get("command")), str(finding.get("check")))
        group = self.groups.get(key)
        if group is None:
            group = self.groups[key] = Group(*key)
        group.add(finding, next(self._order), self.keep)
        self.verdicts[str(finding.get("verdict"))] += 1

    def clear(self) -> None:
        self.groups.clear()
        self.verdicts.clear()

    @property
    def total(self) -> int:
        return sum(self.verdicts.values())

    def ordered(self) -> list[Group]:
        """Groups with the worst verdicts first, then the most findings not obeyed."""
        return sorted(
            self.groups.values(),
            key=lambda g: (
                -g.worst_rank(),
                -g.verdicts.get(NOT_OBEYED, 0) - g.verdicts.get(LOST, 0),
                -g.verdicts.get(PARTIAL, 0) - g.verdicts.get(DEGRADED, 0),
                g.command,
                g.check,
            ),
        )

    def worst_first(self) -> list[dict[str, Any]]:
        """Every kept example of every group, the worst first (earlier first on a tie)."""
        return [
            entry[2]
            for entry in sorted(
                (e for g in self.groups.values() for e in g._worst),
                key=lambda e: (e[0], e[1]),
                reverse=True,
            )
        ]
