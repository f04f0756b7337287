"""A recording judged for a comparison: what it judged, in which window, on what time axis.

The findings come from the response analysis run on the recording as ``analyze`` runs
it (a pipeline stage); the attitude samples and the marks of a replay (the link
diagnostics ``analyzer.replay.player`` writes where its span begins and ends) from the
same pass. A check recording's steps are read as recorded. ``items`` gives what is
paired: the findings about commands (not the feedback's own health) or, for a check
recording, its steps, each with its figures and its time on the comparison's axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from analyzer.analysis.samples import MOTOR_YAW, PITCH, YAW, Sample, sample_from
from analyzer.check.figures import move_figures
from analyzer.check.judge import StepResult
from analyzer.pipeline import Batch
from analyzer.protocol.response_fields import (
    CHECK_LIMIT,
    CHECK_PICTURE,
    CHECK_RATE,
    CHECK_REPEAT,
    CHECK_STOP,
    CHECK_TARGET,
    CHECK_TRACKING,
    FEEDBACK_COMMAND,
)
from analyzer.protocol.types import (
    TOPIC_ANALYSIS_RESPONSE,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
    Event,
)
from analyzer.replay.player import REPLAY, REPLAY_END

STEP = "step"  # the ``check`` of a check step's item
KINDS = {
    CHECK_TARGET: "command",
    CHECK_RATE: "stick movement",
    CHECK_STOP: "stick stop",
    CHECK_REPEAT: "stick cadence",
    CHECK_TRACKING: "tracking session",
    CHECK_PICTURE: "camera command",
    CHECK_LIMIT: "limit",
    STEP: "check step",
}
RESENT = "re-sent target"
AXES = {PITCH: PITCH, YAW: YAW, MOTOR_YAW: MOTOR_YAW}


@dataclass(frozen=True)
class Marks:
    """A replay's span in its recording: the flight and the part of it replayed (the
    flight's clock), the speed, and when the span began and ended on the bench."""

    flight: str
    flight_from: float
    flight_to: float
    speed: float
    began: float
    ended: float | None
    span_start_s: float = 0.0  # the same span in seconds into the flight
    span_end_s: float = 0.0

    def words(self) -> str:
        """'0.0 s to 12.0 s of the flight at 1 times its speed'."""
        return (
            f"{self.span_start_s:.1f} s to {self.span_end_s:.1f} s of the flight at "
            f"{self.speed:g} times its speed"
        )


@dataclass(frozen=True)
class Item:
    """One judged thing to pair: a finding (``check`` names how it was judged) or a check
    step (``check`` is ``step``). ``at``: seconds on the comparison's time axis."""

    kind: str
    command: str
    check: str
    time: float
    at: float
    verdict: str
    detail: str
    figures: dict[str, Any]

    @property
    def key(self) -> tuple[str, str]:
        return (self.command, self.check)


class Judgements:
    """A pipeline sink keeping what a comparison needs of a recording."""

    keeps_items = False

    def __init__(self) -> None:
        self.findings: list[dict[str, Any]] = []
        self.samples: list[Sample] = []
        self.marks: list[Event] = []
        self.first: float | None = None
        self.last: float | None = None

    def handle(self, batch: Batch) -> None:
        for event in batch.events:
            t = event.time
            if event.topic != TOPIC_ANALYSIS_RESPONSE:  # findings carry their command's time
                self.first = t if self.first is None else min(self.first, t)
                self.last = t if self.last is None else max(self.last, t)
            if event.topic == TOPIC_ANALYSIS_RESPONSE:
                self.findings.append(event.to_dict())
            elif event.topic == TOPIC_GIMBAL_ATTITUDE:
                sample = sample_from(t, event.fields, event.warnings)
                if sample is not None:
                    self.samples.append(sample)
            elif event.topic == TOPIC_DIAGNOSTICS and event.fields.get("state") in (
                REPLAY,
                REPLAY_END,
            ):
                self.marks.append(event)

    def close(self) -> None:
        self.findings.sort(key=lambda f: float(f.get("time", 0.0)))
        self.samples.sort(key=lambda s: s.time)


@dataclass
class Judged:
    """A recording's judgements: ``name`` (its path as given), what it is (``described``),
    the findings, a check's steps, the attitude, the replay marks, its first event."""

    name: str
    described: str
    findings: list[dict[str, Any]]
    samples: list[Sample]
    first: float | None
    steps: list[StepResult] = field(default_factory=list)
    marks: Marks | None = None
    tolerance_deg: float = 1.0

    @classmethod
    def of(
        cls,
        name: str,
        described: str,
        judgements: Judgements,
        steps: list[StepResult],
        tolerance_deg: float,
    ) -> Judged:
        return cls(
            name,
            described,
            judgements.findings,
            judgements.samples,
            judgements.first,
            steps,
            replay_marks(judgements.marks),
            tolerance_deg,
        )

    def window(self, other: Judged) -> tuple[float, float, float, float]:
        """(from, to, origin, scale): what is compared (from <= time < to) and its time
        axis. A replay: its span, from where it began (not the centring after its end), in
        the flight's seconds (its time times its speed). The flight of the other's replay
        (a recording that holds the replayed span on the same clock): that span, its last
        frame included, from its start. Else everything, from the first event."""
        if self.marks is not None:
            marks = self.marks
            return marks.began, marks.ended or math.inf, marks.began, marks.speed
        theirs = other.marks
        if theirs is not None and self.covers(theirs):
            return theirs.flight_from, theirs.flight_to + 1e-6, theirs.flight_from, 1.0
        return -math.inf, math.inf, self.first or 0.0, 1.0

    def covers(self, marks: Marks) -> bool:
        """The recording holds the span ``marks`` replayed (it is that flight)."""
        times = [s.time for s in self.samples] or [float(f["time"]) for f in self.findings]
        return bool(times) and times[0] <= marks.flight_to and times[-1] >= marks.flight_from

    def items(self, other: Judged) -> list[Item]:
        """What is paired against ``other``: both check recordings, the steps; else the
        findings about commands in the window (re-sent targets apart from single ones)."""
        start, end, origin, scale = self.window(other)
        if self.steps and other.steps:
            return [
                Item(
                    KINDS[STEP],
                    step.step,
                    STEP,
                    step.started_at,
                    (step.started_at - origin) * scale,
                    step.verdict,
                    step.detail,
                    dict(step.figures),
                )
                for step in self.steps
            ]
        out = []
        for finding in self.findings:
            t = float(finding.get("time", 0.0))
            if finding.get("command") == FEEDBACK_COMMAND or not start <= t < end:
                continue
            check = str(finding.get("check", ""))
            kind = KINDS.get(check, check)
            if check == CHECK_TARGET and int(finding.get("command_count", 1) or 1) > 1:
                kind = RESENT
            out.append(
                Item(
                    kind,
                    str(finding.get("command", "")),
                    check,
                    t,
                    (t - origin) * scale,
                    str(finding.get("verdict", "")),
                    str(finding.get("detail", "")),
                    {**finding, **self._move(finding)},
                )
            )
        return out

    def track(self, other: Judged) -> list[tuple[float, float, float]]:
        """(seconds on the axis, pitch, yaw motor) of the attitude in the window."""
        start, end, origin, scale = self.window(other)
        return [
            ((s.time - origin) * scale, s.pitch, s.motor_yaw)
            for s in self.samples
            if start - 1.0 <= s.time <= end
        ]

    def _move(self, finding: dict[str, Any]) -> dict[str, float]:
        """A target's move measured as the check measures one: slew, settle, latency."""
        axis = AXES.get(str(finding.get("axis", "")))
        target, t = finding.get("target_deg"), float(finding.get("time", 0.0))
        if finding.get("check") != CHECK_TARGET or axis is None:
            return {}
        if not isinstance(target, (int, float)):
            return {}
        end = float(finding.get("observed_at", t))
        before = None
        for s in self.samples:
            if s.time > t:
                break
            before = s
        during = [s for s in self.samples if t < s.time <= end]
        figures = move_figures(axis, float(target), t, before, during, self.tolerance_deg)
        found = figures.as_dict()
        return {k: found[k] for k in ("slew_dps", "settle_s", "latency_s") if k in found}


def replay_marks(events: list[Event]) -> Marks | None:
    """The span a replay recording holds, from its marks (None for any other recording)."""
    begin = next((e for e in events if e.fields.get("state") == REPLAY), None)
    if begin is None:
        return None
    end = next((e for e in events if e.fields.get("state") == REPLAY_END), None)
    fields = begin.fields
    try:
        return Marks(
            str(fields.get("flight", "")),
            float(fields["flight_from"]),
            float(fields["flight_to"]),
            float(fields.get("speed", 1.0)) or 1.0,
            begin.time,
            end.time if end is not None else None,
            float(fields.get("span_start_s", 0.0)),
            float(
                fields.get("span_end_s", float(fields["flight_to"]) - float(fields["flight_from"]))
            ),
        )
    except (KeyError, TypeError, ValueError):
        return None
