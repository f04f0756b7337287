"""A finding of the response analysis: one command judged against the feedback, as an event."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

from analyzer.protocol.response_fields import (
    ALL_VERDICTS,
    CHECK_FEEDBACK,
    CHECK_FEEDBACK_GAP,
    CHECK_LIMIT,
    CHECK_RATE,
    CHECK_REPEAT,
    CHECK_STOP,
    CHECK_TARGET,
    CHECK_TRACKING,
    CHECKS,
    DEGRADED,
    FEEDBACK_COMMAND,
    HEALTH_VERDICTS,
    HEALTHY,
    LOST,
    NOT_OBEYED,
    OBEYED,
    PARTIAL,
    UNKNOWN,
    VERDICTS,
)
from analyzer.protocol.types import TOPIC_ANALYSIS_RESPONSE, Event


class Timed(Protocol):
    """The first and last time of a run's input (a Tally has them)."""

    first_time: float | None
    last_time: float | None


_RANK = {OBEYED: 0, UNKNOWN: 1, PARTIAL: 2, NOT_OBEYED: 3}

SOURCE = "analysis"


def worst(*verdicts: str) -> str:
    """The verdict that says the least good about the gimbal."""
    return max(verdicts, key=_RANK.__getitem__)


@dataclass(slots=True)
class ResponseFinding:
    """One judgement; ``extra`` holds the optional fields of analyzer.protocol.response_fields."""

    command: str
    time: float
    check: str
    verdict: str
    detail: str
    extra: dict[str, Any] = field(default_factory=dict)

    def to_event(self) -> Event:
        fields: dict[str, Any] = {
            "command": self.command,
            "check": self.check,
            "verdict": self.verdict,
            "detail": self.detail,
        }
        for key, value in self.extra.items():
            if value is None:
                continue  # absent rather than null
            fields[key] = round(value, 3) if type(value) is float else value
        return Event(TOPIC_ANALYSIS_RESPONSE, self.time, SOURCE, fields)


STOPPED_BEFORE = "the feedback stopped before it"


def cut_words(
    since: float, until: float, seen: float | None, ended: float | None, wait: float
) -> str:
    """Why the feedback a judgement waited for (from ``since``, the command, to
    ``until``) did not reach ``until``, in words; '' when it did. ``seen``: the last
    feedback message; ``ended``: the end of the input, when it ended (the input's end
    is the reason unless the feedback had been silent for longer than ``wait``)."""
    if seen is not None and seen >= until:
        return ""
    if ended is not None and (seen is None or ended - seen <= wait):
        return f"the input ended {max(0.0, ended - since):.1f} s later"
    if seen is None or seen <= since:
        return STOPPED_BEFORE
    return f"the feedback stopped {seen - since:.1f} s after it"


def no_feedback_until(why: str) -> str:
    """'no attitude feedback came before <why>' in words that read."""
    if why == STOPPED_BEFORE:
        return "no attitude feedback came after it (the feedback had stopped)"
    return f"no attitude feedback came {why if why.startswith('within') else f'before {why}'}"


def verdict_line(counts: dict[str, int]) -> str:
    """'3 obeyed, 1 partial, 2 not obeyed, 0 unknown' in a fixed order."""
    return ", ".join(f"{counts.get(v, 0)} {v.replace('_', ' ')}" for v in VERDICTS)


__all__ = [
    "ALL_VERDICTS",
    "CHECKS",
    "CHECK_FEEDBACK",
    "CHECK_FEEDBACK_GAP",
    "CHECK_LIMIT",
    "CHECK_RATE",
    "CHECK_REPEAT",
    "CHECK_STOP",
    "CHECK_TARGET",
    "CHECK_TRACKING",
    "DEGRADED",
    "FEEDBACK_COMMAND",
    "HEALTHY",
    "HEALTH_VERDICTS",
    "LOST",
    "NOT_OBEYED",
    "OBEYED",
    "PARTIAL",
    "UNKNOWN",
    "VERDICTS",
    "ResponseFinding",
    "cut_words",
    "no_feedback_until",
    "verdict_line",
    "worst",
]


def untimed(tally: Timed, findings: list[Any]) -> bool:
    """True when findings were made of an input without a clock (a raw byte dump): every
    "0.0 s later" would be nonsense, so they are not reported."""
    return bool(findings) and (tally.first_time is None or tally.first_time == tally.last_time)
