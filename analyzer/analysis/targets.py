"""Target-type commands (specified_angle, look_down, forward): reached, how fast, how well."""

from __future__ import annotations

import math
from dataclasses import dataclass

from analyzer.analysis.findings import NOT_OBEYED, OBEYED, PARTIAL, UNKNOWN, no_feedback_until
from analyzer.analysis.samples import MOTOR_YAW, PITCH, PITCH_LIMITS, Sample
from analyzer.analysis.yaw_geometry import (
    angle_error,
    motor_limit,
    motor_target,
    reachable,
    shortest_difference,
    travel,
)

STILL_DEG = 0.2  # two samples closer than this: the gimbal has stopped
SETTLED_S = 1.0  # still this long before another command: its answer is final


@dataclass(frozen=True)
class AxisGoal:
    """One angle a command asks for."""

    axis: str
    target: float
    label: str  # how the detail names it: "pitch", "yaw", "yaw (airframe)"

    def error(self, sample: Sample) -> float:
        """Target minus the angle (the short way round for yaw)."""
        return angle_error(self.axis, self.target, sample)

    def travel(self, sample: Sample) -> float:
        """The signed turn still needed, along the way the axis can turn."""
        return travel(self.axis, self.target, sample)


@dataclass
class AxisResult:
    """How one axis answered."""

    goal: AxisGoal
    verdict: str
    text: str
    response_s: float | None = None
    error_deg: float | None = None
    overshoot_deg: float | None = None
    start_deg: float | None = None
    final_deg: float | None = None
    limit_deg: float | None = None


def _fmt(value: float) -> str:
    """An angle as the sentence says it: from the value the finding's JSON carries
    (rounded to 3 decimals), so the two never round apart (4.6499 is '4.7' in both)."""
    return f"{round(value, 3):.1f}"


def judge_axis(
    goal: AxisGoal,
    command_time: float,
    before: Sample | None,
    samples: list[Sample],
    tolerance: float,
    allowed_s: float,
    *,
    cut_short: str = "",
) -> AxisResult:
    """Judge one axis from the samples after the command (``samples``, oldest first).

    ``before`` is the last sample before the command. ``cut_short`` names what ended
    the time allowed early (another command, the end of the input), if anything.
    Errors are the shortest way round for yaw; directions (moved the other way, gone
    past the target) follow the way the axis can turn.
    """
    axis, target = goal.axis, goal.target
    if not samples:
        why = cut_short or f"within {allowed_s:g} s"
        return AxisResult(goal, UNKNOWN, no_feedback_until(why))
    start = before if before is not None else samples[0]
    start_value = start.value(axis)
    first_error = goal.error(start)
    first_travel = goal.travel(start)
    errors = [goal.error(s) for s in samples]
    travels = [goal.travel(s) for s in samples]
    last = samples[-1]
    final_error = errors[-1]
    result = AxisResult(
        goal, OBEYED, "", error_deg=final_error, start_deg=start_value, final_deg=last.value(axis)
    )
    sign = math.copysign(1.0, first_travel) if abs(first_error) > tolerance else 0.0
    # Reached: within tolerance, or gone past the target (an overshoot between two samples).
    reached = next(
        (
            i
            for i, (e, w) in enumerate(zip(errors, travels, strict=True))
            if abs(e) <= tolerance or sign * w < 0
        ),
        None,
    )
    if reached is not None:
        past = [-sign * w for w in travels[reached:]] if sign else [0.0]
        return _reached(
            result, samples[reached].time - command_time, max(0.0, *past), last, tolerance
        )
    moved = first_travel - travels[-1]
    where = f"{_fmt(last.value(axis))}, {_fmt(abs(final_error))} deg from the target"
    if cut_short and not _settled(travels, samples):
        result.verdict = UNKNOWN
        result.text = (
            f"{goal.label} not at {_fmt(target)} yet when {cut_short} "
            f"(at {where}, moved {_fmt(moved)} deg)"
        )
        return result
    within = f"before {cut_short}" if cut_short else f"within {allowed_s:g} s"
    head = f"{goal.label} {_fmt(target)} not reached {within}: "
    if axis != PITCH and not reachable(axis, target, last):
        nearest = _nearest_limit(goal, last, tolerance)
        if nearest is not None:
            result.verdict = PARTIAL
            result.limit_deg = nearest
            result.text = (
                f"{goal.label} {_fmt(target)} is out of the yaw motor's reach: "
                f"{_needs(goal, last)}; it went to its limit {_fmt(nearest)}, "
                f"{_fmt(abs(final_error))} deg from the target, as near as it can get"
            )
            return result
    if abs(moved) < tolerance:
        result.verdict = NOT_OBEYED
        # The angles the finding carries (start_deg, final_deg): less than the tolerance apart.
        text = f"never moved (from {_fmt(start_value)} to {where})"
    elif abs(first_error) > tolerance and math.copysign(1.0, moved) != sign:
        result.verdict = NOT_OBEYED
        text = f"moved the other way, to {where}"
    else:
        result.verdict = PARTIAL
        text = _short_of_it(travels, where)
    result.text = head + text + _limit_note(goal, last, result)
    return result


def _reached(
    result: AxisResult, response_s: float, overshoot: float, last: Sample, tolerance: float
) -> AxisResult:
    """The target reached ``response_s`` after the command, gone past it by ``overshoot``:
    in words, and partly obeyed when the axis drifted off again."""
    goal = result.goal
    result.response_s, result.overshoot_deg = response_s, overshoot
    text = f"{goal.label} reached {_fmt(goal.target)} in {response_s:.1f} s"
    if overshoot > tolerance:
        text += f", overshooting by {_fmt(overshoot)} deg"
    final_error = goal.error(last)
    if abs(final_error) > tolerance:
        result.verdict = PARTIAL
        text += f" but then drifted to {_fmt(last.value(goal.axis))} ({_fmt(final_error)} off)"
    result.text = text
    return result


def _short_of_it(travels: list[float], where: str) -> str:
    """An axis that moved the right way but not far enough: stopped, or still moving."""
    step = travels[-2] - travels[-1] if len(travels) > 1 else 0.0
    if abs(step) < STILL_DEG:
        return f"stopped short at {where}"
    return f"still on its way, at {where}"


def _limit_note(goal: AxisGoal, last: Sample, result: AxisResult) -> str:
    """'; it is at its yaw motor limit 170.0' or why the target cannot be reached, if so."""
    axis = goal.axis
    physical = PITCH if axis == PITCH else MOTOR_YAW
    limit = last.at_limit(physical)
    if limit is not None:
        result.limit_deg = limit
        return f"; it is at its {physical.replace('_', ' ')} limit {_fmt(limit)}"
    if axis == PITCH:
        lo, hi = PITCH_LIMITS
        if not lo <= goal.target <= hi:
            return f"; the target is outside the pitch range {_fmt(lo)}..{_fmt(hi)}"
        return ""
    if not reachable(axis, goal.target, last):
        return f"; the target is out of the yaw motor's reach: {_needs(goal, last)}"
    return ""


def _needs(goal: AxisGoal, last: Sample) -> str:
    limit = motor_limit(last)
    angle = motor_target(goal.axis, goal.target, last)
    return f"it needs the motor at {_fmt(angle)} from the nose, beyond its range +-{limit:g}"


def _nearest_limit(goal: AxisGoal, last: Sample, tolerance: float) -> float | None:
    """The motor limit the gimbal sits at, when no angle it can reach points nearer."""
    limit = last.at_limit(MOTOR_YAW)
    if limit is None:
        return None
    wanted = motor_target(goal.axis, goal.target, last)
    best = min(abs(shortest_difference(wanted, end)) for end in (-limit, limit))
    return limit if abs(shortest_difference(wanted, limit)) <= best + tolerance else None


def _settled(travels: list[float], samples: list[Sample]) -> bool:
    """The last samples span SETTLED_S or more without the angle changing."""
    last, last_time = travels[-1], samples[-1].time
    for w, s in zip(reversed(travels), reversed(samples), strict=True):
        if abs(w - last) >= STILL_DEG:
            return False
        if last_time - s.time >= SETTLED_S:
            return True
    return False
