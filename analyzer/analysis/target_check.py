"""Target-type commands waiting for their answer, and the finding that judges each one."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

from analyzer.analysis.findings import CHECK_TARGET, ResponseFinding, worst
from analyzer.analysis.samples import MOTOR_YAW, PITCH, YAW, Sample
from analyzer.analysis.targets import AxisGoal, judge_axis
from analyzer.analysis.yaw_geometry import shortest_difference
from analyzer.analysis.yaw_reference import YawCommand, choose_reference, wrong_frame

LOOK_DOWN_DEG = -90.0


class Tolerance(Protocol):
    """The analysis' settings, as far as a target's tolerance goes."""

    @property
    def tolerance_deg(self) -> float: ...


@dataclass
class TargetCheck:
    """A command asking for angles; ``yaw`` when it is a specified_angle yaw target, whose
    reference (and so its goal's axis) is chosen when it is judged.

    A ground station may re-send the same target until it is reached: each re-send is
    counted here (``count``, ``last_sent``) instead of starting a judgement of its own.
    Once judged (``finding``), the check is kept while re-sends still come, so that they
    are counted in the one finding it gives."""

    command: str
    time: float
    goals: tuple[AxisGoal, ...]
    deadline: float
    yaw: YawCommand | None = None
    count: int = 1
    last_sent: float = field(init=False)
    finding: ResponseFinding | None = None

    def __post_init__(self) -> None:
        self.last_sent = self.time

    def axes(self) -> set[str]:
        """The axes it takes over: pitch, yaw (both yaw references)."""
        return {PITCH if g.axis == PITCH else YAW for g in self.goals}

    def repeated_by(self, other: TargetCheck, tolerance: float) -> bool:
        """``other`` asks for this check's targets again: the same command, axes and yaw
        frame, every target within ``tolerance`` degrees (yaw the short way round)."""
        if other.command != self.command or len(other.goals) != len(self.goals):
            return False
        mine_yaw, their_yaw = self.yaw, other.yaw
        if (mine_yaw is None) != (their_yaw is None):
            return False
        if (
            mine_yaw is not None
            and their_yaw is not None
            and mine_yaw.airframe != their_yaw.airframe
        ):
            return False
        for mine, theirs in zip(self.goals, other.goals, strict=True):
            if mine.axis != theirs.axis:
                return False
            difference = theirs.target - mine.target
            if mine.axis != PITCH:
                difference = shortest_difference(mine.target, theirs.target)
            if abs(difference) > tolerance:
                return False
        return True

    def met(self, sample: Sample, settings: Tolerance) -> bool:
        """``sample`` is within the tolerance of every target (a yaw one in either frame:
        whichever it is judged in, it is met)."""
        tolerance = settings.tolerance_deg
        if self.yaw is not None:
            target = self.yaw.target
            return any(
                abs(shortest_difference(target, sample.value(axis))) <= tolerance
                for axis in (YAW, MOTOR_YAW)
            )
        return all(abs(goal.error(sample)) <= tolerance for goal in self.goals)

    def resent(self, t: float) -> None:
        """The same target sent again at ``t``."""
        self.count += 1
        self.last_sent = t

    def release(self) -> ResponseFinding:
        """The judged finding, with the re-sends counted in."""
        finding = self.finding
        assert finding is not None
        finding.extra["command_count"] = self.count
        if self.count > 1:
            span = self.last_sent - self.time
            finding.extra["resent_for_s"] = span
            finding.detail += f"; sent {self.count} times over {span:.1f} s"
        return finding


def target_check(
    name: str, t: float, fields: dict[str, Any], deadline: float, fc_attitude: bool
) -> TargetCheck | None:
    """The check of a specified_angle, look_down or forward command (None: nothing to see).

    ``fc_attitude``: the flight controller's attitude (FF13) was seen shortly before."""
    if name == "look_down":
        return TargetCheck(name, t, (AxisGoal(PITCH, LOOK_DOWN_DEG, "pitch"),), deadline)
    if name == "forward":
        goals = (AxisGoal(PITCH, 0.0, "pitch"), AxisGoal(MOTOR_YAW, 0.0, "yaw (airframe)"))
        return TargetCheck(name, t, goals, deadline)
    if name != "specified_angle":
        return None
    axis = fields.get("axis")
    if axis == "pitch" and isinstance(fields.get("pitch_deg"), (int, float)):
        goal = AxisGoal(PITCH, float(fields["pitch_deg"]), "pitch")
        return TargetCheck(name, t, (goal,), deadline)
    if axis != "yaw" or not isinstance(fields.get("yaw_deg"), (int, float)):
        return None  # zoom: the feedback does not report it
    yaw = YawCommand(
        target=float(fields["yaw_deg"]),
        airframe=fields.get("coordinate_system") == "airframe",
        fc_attitude=fc_attitude,
        stream=fields.get("transport") == "stream",
    )
    return TargetCheck(name, t, (AxisGoal(YAW, yaw.target, "yaw"),), deadline, yaw)


def judge_target(
    check: TargetCheck,
    before: Sample | None,
    samples: list[Sample],
    tolerance: float,
    allowed_s: float,
    cut_short: str,
) -> ResponseFinding:
    """The finding of ``check`` from the sample before it and those in its time."""
    goals = check.goals
    labels: dict[str, str] = {}
    reference = None
    if check.yaw is not None:
        reference = choose_reference(check.yaw, ([before] if before else []) + samples)
        goals = (reference.goal(check.yaw),)
        labels = {"yaw_reference": reference.name, "reference_reason": reference.reason}
    results = []
    for goal in goals:
        result = judge_axis(
            goal, check.time, before, samples, tolerance, allowed_s, cut_short=cut_short
        )
        if reference is not None:
            result = wrong_frame(reference, result, samples[-1] if samples else None, tolerance)
        results.append(result)
    verdict = worst(*(r.verdict for r in results))
    detail = "; ".join(dict.fromkeys(r.text for r in results))
    if reference is not None:
        detail += f"; {reference.note()}"
    extra: dict[str, str | float | None] = {
        "axis": "+".join(g.axis for g in goals),
        "target_deg": goals[0].target,
        **labels,
    }
    errors = [r.error_deg for r in results if r.error_deg is not None]
    if errors:
        extra["error_deg"] = max(errors, key=abs)
    responses = [r.response_s for r in results]
    if responses and all(r is not None for r in responses):
        extra["response_s"] = max(r for r in responses if r is not None)
    overshoots = [r.overshoot_deg for r in results if r.overshoot_deg is not None]
    if overshoots:
        extra["overshoot_deg"] = max(overshoots)
    if len(results) == 1:
        extra["start_deg"] = results[0].start_deg
        extra["final_deg"] = results[0].final_deg
    limits = [r.limit_deg for r in results if r.limit_deg is not None]
    if limits:
        extra["limit_deg"] = limits[0]
    if samples:
        extra["observed_at"] = samples[-1].time
    return ResponseFinding(check.command, check.time, CHECK_TARGET, verdict, detail, extra)
