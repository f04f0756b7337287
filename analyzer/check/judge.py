"""A step's verdict: the response analysis' findings, the measured figures and the pass limits."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from analyzer.analysis.findings import (
    CHECK_RATE,
    CHECK_REPEAT,
    CHECK_STOP,
    CHECK_TARGET,
    CHECK_TRACKING,
    NOT_OBEYED,
    OBEYED,
    PARTIAL,
    UNKNOWN,
    worst,
)
from analyzer.analysis.rates import LATE_S
from analyzer.analysis.response import Settings
from analyzer.analysis.samples import MOTOR_YAW, PITCH, YAW, Sample
from analyzer.check.figures import (
    feedback_figures,
    longest_silence,
    move_figures,
    rate_figure,
)
from analyzer.check.steps import Hold, Listen, Plan, Send
from analyzer.feedback_track import EXPECTED_FEEDBACK_HZ, FEEDBACK_TOLERANCE, GAP_THRESHOLD_S
from analyzer.protocol.check_fields import FAIL, PASS, SKIPPED
from analyzer.protocol.response_fields import CHECK_PICTURE, REFERENCE_AIRFRAME
from analyzer.timefmt import UTC

JUDGED_CHECKS = frozenset(
    {CHECK_TARGET, CHECK_RATE, CHECK_STOP, CHECK_REPEAT, CHECK_TRACKING, CHECK_PICTURE}
)
PERIOD_S = 1.0 / EXPECTED_FEEDBACK_HZ


@dataclass(frozen=True)
class Limits:
    """The pass limits: the analysis' settings, the slowest slew, how far a speed may be off."""

    settings: Settings = field(default_factory=Settings)
    min_slew_dps: float = 30.0
    speed_tolerance: float = 0.25


@dataclass
class StepResult:
    """One step's verdict, with the figures it measured."""

    step: str
    verdict: str
    detail: str
    figures: dict[str, Any] = field(default_factory=dict)
    index: int = 0
    started_at: float = 0.0
    duration_s: float = 0.0
    findings: list[str] = field(default_factory=list)

    def fields(self) -> dict[str, Any]:
        """The /check/steps event fields and the --json object: figures as top-level keys."""
        out: dict[str, Any] = {"step": self.step, "verdict": self.verdict, "detail": self.detail}
        for key, value in self.figures.items():
            out[key] = round(value, 3) if isinstance(value, float) else value
        out.update(
            index=self.index,
            started_at=round(self.started_at, 3),
            duration_s=round(self.duration_s, 2),
            findings=list(self.findings),
        )
        return out


@dataclass
class Evidence:
    """What one step sent and saw: its judged commands (name, time) and the feedback."""

    plan: Plan
    started_at: float
    ended_at: float
    judged: list[tuple[Send | Hold, float, float]]  # action, its first and last send time
    samples: list[Sample]
    feedback_times: list[float]
    damaged: int
    findings: dict[int, list[dict[str, Any]]]  # index into ``judged`` -> its findings


def required_checks(action: Send | Hold) -> tuple[str, ...]:
    """The checks whose findings decide a judged action: a speed held, its rate and that
    it stopped when the commands did."""
    return (CHECK_RATE, CHECK_STOP) if isinstance(action, Hold) else (action.check,)


def judge_feedback(evidence: Evidence) -> tuple[str, str, dict[str, Any]]:
    start, end = evidence.started_at, evidence.ended_at
    figures = feedback_figures(evidence.feedback_times, evidence.damaged, start, end, PERIOD_S)
    numbers: dict[str, Any] = dict(figures.as_dict())
    span = end - start
    if not figures.messages:
        damaged = f", {figures.crc_errors} damaged" if figures.crc_errors else ""
        text = f"no feedback: no whole message in {span:.1f} s ({figures.lost} lost{damaged})"
        return FAIL, text, numbers
    problems = []
    period = figures.period_s
    if period is not None and abs(period - PERIOD_S) > FEEDBACK_TOLERANCE * PERIOD_S:
        problems.append(f"a message every {period:.2f} s instead of {PERIOD_S:.2f}")
    if figures.lost:
        problems.append(f"{figures.lost} of {figures.messages + figures.lost} messages lost")
    if figures.crc_errors:
        problems.append(f"{figures.crc_errors} damaged (CRC error / incomplete)")
    if figures.longest_gap_s > GAP_THRESHOLD_S:
        problems.append(f"a silence of {figures.longest_gap_s:.1f} s")
    if problems:
        return FAIL, f"over {span:.1f} s: " + ", ".join(problems), numbers
    every = f"every {period:.2f} s" if period is not None else ""
    text = f"{figures.messages} messages {every} over {span:.1f} s, none lost, no CRC error"
    return PASS, text, numbers


def _finding_line(f: dict[str, Any]) -> str:
    return f"{f.get('command')} {f.get('check')}: {f.get('verdict')}"


def _move_axis(plan: Plan, findings: list[dict[str, Any]]) -> str:
    """The axis the figures are measured on: for a yaw target the reference the analysis
    judged it in (one truth: the same yaw as the verdict)."""
    if plan.axis == YAW:
        for f in findings:
            if f.get("yaw_reference") == REFERENCE_AIRFRAME:
                return MOTOR_YAW
    return plan.axis


@dataclass
class Measured:
    """A step's figures, how they miss the pass limits (``problems``), and those the
    feedback did not allow to be measured (``unmeasured``)."""

    figures: dict[str, Any] = field(default_factory=dict)
    problems: list[str] = field(default_factory=list)
    unmeasured: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)  # said, but no failure (a late start)


def measure(evidence: Evidence, limits: Limits) -> Measured:
    """The figures of a step's judged commands, and how they miss the pass limits."""
    plan = evidence.plan
    measured = Measured()
    figures = measured.figures
    tolerance = limits.settings.tolerance_deg
    problems = measured.problems
    for number, (action, first, last) in enumerate(evidence.judged):
        found = evidence.findings.get(number, [])
        # A message dated late (its segments came far apart) measured earlier: left out.
        samples = [s for s in evidence.samples if not s.late]
        during = [s for s in samples if first < s.time <= evidence.ended_at]
        before = None
        for s in samples:
            if s.time <= first:
                before = s
        if isinstance(action, Hold):
            axis = MOTOR_YAW if action.pan_dps else PITCH
            asked = action.pan_dps or action.tilt_dps
            # The analysis' measured rate (its ratio of the speed asked, late motion and
            # all); without its verdict, the slope of the feedback while the speed held.
            key = f"measured_{'pan' if action.pan_dps else 'tilt'}_dps"
            rates = [f[key] for f in found if isinstance(f.get(key), (int, float))]
            inside = [s for s in during if s.time <= last + 0.05]
            points = ([before] if before else []) + inside
            rate = rates[0] if rates else rate_figure(axis, points, tolerance)
            figures["asked_dps"] = asked
            if rate is None:
                measured.unmeasured.append("the rate could not be measured: too little feedback")
            else:
                figures["rate_dps"] = rate
                off = abs(rate - asked) / abs(asked)
                if off > limits.speed_tolerance:
                    problems.append(
                        f"turned at {rate:.1f} deg/s for {asked:g} asked "
                        f"({rate / asked * 100:.0f} %, more than "
                        f"{limits.speed_tolerance * 100:g} % off)"
                    )
        elif isinstance(action, Send) and action.check == CHECK_PICTURE:
            for f in found:  # the zoom in's scale, and the zoom back's
                scale = f.get("scale")
                if f.get("check") == CHECK_PICTURE and isinstance(scale, (int, float)):
                    figures["scale" if "scale" not in figures else "scale_back"] = scale
        elif plan.axis and plan.target is not None and isinstance(action, Send) and action.goals:
            axis = _move_axis(plan, found)
            move = move_figures(axis, plan.target, first, before, during, tolerance)
            figures.update(move.as_dict())
            figures["axis"] = axis
            figures["target_deg"] = plan.target
            if move.latency_s is not None and move.latency_s >= LATE_S:
                measured.notes.append(f"it began to move about {move.latency_s:.1f} s late")
            if move.slew_dps is None:
                measured.unmeasured.append(
                    "the slew rate could not be measured: fewer than 2 feedback samples in "
                    "the moving part"
                )
            elif move.slew_dps < limits.min_slew_dps:
                problems.append(
                    f"moved at {move.slew_dps:.1f} deg/s, slower than the minimum "
                    f"{limits.min_slew_dps:g} deg/s"
                )
    return measured


def _pairs(evidence: Evidence) -> list[tuple[str, str]]:
    """(verdict, detail) of every deciding finding; unknown for a judged command the
    analysis gave no verdict on."""
    pairs: list[tuple[str, str]] = []
    for number, (action, _, _) in enumerate(evidence.judged):
        found = [f for f in evidence.findings.get(number, []) if f.get("check") in JUDGED_CHECKS]
        name = action.name if isinstance(action, Send) else "gimbal_control"
        given = {f.get("check") for f in found}
        if not set(required_checks(action)) <= given:
            missing = ", ".join(c for c in required_checks(action) if c not in given)
            pairs.append((UNKNOWN, f"{name}: the analysis gave no verdict ({missing})"))
            continue
        pairs += [(str(f.get("verdict")), str(f.get("detail"))) for f in found]
    return pairs


def undecided(evidence: Evidence, measured: Measured, pairs: list[tuple[str, str]]) -> str:
    """Why the feedback did not allow the step to be judged ('' when it did): a judged
    command the analysis found unknown, or a figure it could not measure; said as the
    silence when the feedback stopped during the step."""
    unknown = [d for v, d in pairs if v == UNKNOWN]
    if not (unknown or measured.unmeasured):
        return ""
    silence, since = longest_silence(
        evidence.feedback_times, evidence.started_at, evidence.ended_at
    )
    if silence > GAP_THRESHOLD_S:
        return (
            # a verdict's sentence is data (the JSON, the recording): in UTC, always
            f"no feedback for {silence:.1f} s during the step (from {UTC.format_clock(since)}): "
            "it cannot be judged"
        )
    text = "; ".join(unknown + measured.unmeasured)
    if "no attitude feedback" in text or "no feedback" in text:
        text = "no feedback: " + text
    return text


def judge_motion(evidence: Evidence, limits: Limits) -> tuple[str, str, dict[str, Any], list[str]]:
    """Verdict, detail, figures and finding lines of a step that sends judged commands.

    A step the gimbal did not obey fails with the analysis' words; one the feedback did
    not allow to be judged fails as such (``undecided``: messages lost during it change
    nothing when the verdicts and figures could be had)."""
    measured = measure(evidence, limits)
    figures, problems = measured.figures, measured.problems
    lines = [_finding_line(f) for fs in evidence.findings.values() for f in fs]
    pairs = _pairs(evidence)
    verdict = worst(*(v for v, _ in pairs)) if pairs else UNKNOWN
    bad = [d for v, d in pairs if v not in (OBEYED, UNKNOWN)]
    if verdict in (PARTIAL, NOT_OBEYED):
        return FAIL, "; ".join(bad + problems), figures, lines
    why = undecided(evidence, measured, pairs)
    if why:
        return FAIL, why, figures, lines
    said = list(dict.fromkeys(d for _, d in pairs)) + measured.notes
    if problems:
        return FAIL, "; ".join(problems + said), figures, lines
    return PASS, "; ".join(said), figures, lines


def judge(evidence: Evidence, limits: Limits) -> tuple[str, str, dict[str, Any], list[str]]:
    """Verdict, one-line detail, figures and the finding lines of a finished step."""
    plan = evidence.plan
    if any(isinstance(a, Listen) for a in plan.actions):
        verdict, text, figures = judge_feedback(evidence)
        return verdict, text, figures, []
    if plan.skipped:
        return SKIPPED, plan.skipped, {}, []
    return judge_motion(evidence, limits)
