"""tracking sessions against the feedback's tracking flag: when one starts, and at its stop."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from analyzer.analysis.findings import (
    CHECK_TRACKING,
    NOT_OBEYED,
    OBEYED,
    UNKNOWN,
    ResponseFinding,
    no_feedback_until,
)
from analyzer.analysis.samples import Sample


@dataclass
class TrackingSession:
    """A tracker at work: its first ``tracking`` command and the box updates after it,
    until ``tracking_stop`` (or until the feedback shows the flag off after it was on)."""

    start: float
    count: int = 1
    last: float = field(init=False)
    seen_on: bool = False  # the feedback has shown the flag on since the start

    def __post_init__(self) -> None:
        self.last = self.start

    def update(self, t: float) -> None:
        """Another ``tracking`` command (the box moved) while the session is on."""
        self.count += 1
        self.last = t

    def figures(self, end: float | None = None) -> dict[str, Any]:
        """command_count and updates_hz (and duration_s up to ``end``) of the session."""
        out: dict[str, Any] = {"command_count": self.count}
        span = self.last - self.start
        if self.count > 1 and span > 0:
            out["updates_hz"] = (self.count - 1) / span
        if end is not None:
            out["duration_s"] = end - self.start
        return out


@dataclass
class TrackingCheck:
    """A tracking (``want`` on) or tracking_stop (``want`` off) waiting for the flag;
    ``session`` is the session it starts or ends."""

    command: str
    time: float
    want: bool
    deadline: float  # the command's time and the flag's allowance
    session: TrackingSession | None = None


def judge_tracking(
    check: TrackingCheck,
    sample: Sample | None,
    seen: list[Sample],
    cut_short: str,
    allowed_s: float,
) -> ResponseFinding:
    """``sample``: the first attitude message showing the flag as wanted (obeyed); else
    ``seen``, the messages of the allowance, all showing it as it was: not obeyed, or
    unknown when ``cut_short`` names what ended the allowance early."""
    flag = "on" if check.want else "off"
    extra: dict[str, Any] = {}
    if check.session is not None:
        extra.update(check.session.figures(None if check.want else check.time))
    if sample is not None:
        extra["response_s"] = sample.time - check.time
        extra["observed_at"] = sample.time
        text = f"the feedback's tracking flag went {flag} after {extra['response_s']:.2f} s"
        return ResponseFinding(check.command, check.time, CHECK_TRACKING, OBEYED, text, extra)
    if not seen:
        why = cut_short or f"within {allowed_s:g} s"
        text = f"{no_feedback_until(why)}: the tracking flag could not be checked"
        return ResponseFinding(check.command, check.time, CHECK_TRACKING, UNKNOWN, text, extra)
    extra["observed_at"] = seen[-1].time
    span = seen[-1].time - check.time
    verdict = UNKNOWN if cut_short else NOT_OBEYED
    other = "off" if check.want else "on"
    if cut_short:
        text = f"the feedback's tracking flag stayed {other} for {span:.1f} s, until {cut_short}"
    else:
        n = len(seen)
        text = (
            f"the feedback's tracking flag stayed {other} through the {allowed_s:g} s allowed "
            f"({n} attitude message{'s' if n > 1 else ''}, the last {span:.1f} s after "
            "the command)"
        )
    return ResponseFinding(check.command, check.time, CHECK_TRACKING, verdict, text, extra)


def nothing_to_stop(
    t: float, before: Sample | None, *, seen_on: bool, session: TrackingSession | None = None
) -> ResponseFinding:
    """A tracking_stop at ``t`` when the feedback did not show tracking on: nothing to obey.
    ``before``: the last attitude message before it; ``seen_on``: any showed the flag on;
    ``session``: the session it ends, if one was on."""
    if not seen_on:
        text = "tracking was never on in the feedback: there was nothing to stop"
    elif before is None:
        text = "no attitude feedback before the command: whether tracking was on is not known"
    else:
        text = "tracking was already off: there was nothing to stop"
    extra: dict[str, Any] = {"observed_at": before.time} if before is not None else {}
    if session is not None:
        extra.update(session.figures(t))
    return ResponseFinding("tracking_stop", t, CHECK_TRACKING, UNKNOWN, text, extra)
