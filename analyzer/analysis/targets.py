"""Target-type commands (specified_angle, look_down, forward): reached, how fast, how well."""

from __future__ import annotations

import math
from dataclasses import dataclass

from analyzer.analysis.findings import NOT_OBEYED, OBEYED, PARTIAL, UNKNOWN
from analyzer.analysis.samples import Sample, difference

STILL_DEG = 0.2  # two samples closer than this: the gimbal has stopped
SETTLED_S = 1.0  # still this long before another command: its answer is final


@dataclass(frozen=True)
class AxisGoal:
    """One angle a command asks for."""

    axis: str
    target: float
    label: str  # how the detail names it: "pitch", "yaw", "yaw (airframe)"


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
    return f"{value:.1f}"


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
    """
    axis, target = goal.axis, goal.target
    if not samples:
        why = cut_short or f"within {allowed_s:g} s"
        return AxisResult(goal, UNKNOWN, f"no attitude feedback came {_after(why)}")
    start = before if before is not None else samples[0]
    start_value = start.value(axis)
    first_error = difference(axis, target, start_value)
    errors = [difference(axis, target, s.value(axis)) for s in samples]
    last = samples[-1]
    final_error = errors[-1]
    result = AxisResult(
        goal, OBEYED, "", error_deg=final_error, start_deg=start_value, final_deg=last.value(axis)
    )
    sign = math.copysign(1.0, first_error) if abs(first_error) > tolerance else 0.0
    # Reached: within tolerance, or gone past the target (an overshoot between two samples).
    reached = next((i for i, e in enumerate(errors) if abs(e) <= tolerance or sign * e < 0), None)
    limits = last.limits(axis)
    beyond = limits is not None and not limits[0] <= goal.target <= limits[1]
    if reached is not None:
        result.response_s = samples[reached].time - command_time
        past = [-sign * e for e in errors[reached:]] if sign else [0.0]
        result.overshoot_deg = max(0.0, *past)
        text = f"{goal.label} reached {_fmt(target)} in {result.response_s:.1f} s"
        if result.overshoot_deg > tolerance:
            text += f", overshooting by {_fmt(result.overshoot_deg)} deg"
        if abs(final_error) > tolerance:
            result.verdict = PARTIAL
            text += f" but then drifted to {_fmt(last.value(axis))} ({_fmt(final_error)} off)"
        result.text = text
        return result
    moved = difference(axis, last.value(axis), start_value)
    where = f"{_fmt(last.value(axis))}, {_fmt(abs(final_error))} deg from the target"
    if cut_short and not _settled(axis, samples):
        result.verdict = UNKNOWN
        result.text = (
            f"{goal.label} not at {_fmt(target)} yet when {cut_short} "
            f"(at {where}, moved {_fmt(moved)} deg)"
        )
        return result
    within = f"before {cut_short}" if cut_short else f"within {allowed_s:g} s"
    head = f"{goal.label} {_fmt(target)} not reached {within}: "
    if abs(moved) < tolerance:
        result.verdict = NOT_OBEYED
        text = f"never moved (stayed at {_fmt(start_value)})"
    elif abs(first_error) > tolerance and math.copysign(1.0, moved) != math.copysign(
        1.0, first_error
    ):
        result.verdict = NOT_OBEYED
        text = f"moved the other way, to {where}"
    else:
        result.verdict = PARTIAL
        step = 0.0
        if len(samples) > 1:
            step = difference(axis, last.value(axis), samples[-2].value(axis))
        if abs(step) < STILL_DEG:
            text = f"stopped short at {where}"
        else:
            text = f"still on its way, at {where}"
    limit = last.at_limit(axis)
    if limit is not None:
        result.limit_deg = limit
        text += f"; it is at its {axis.replace('_', ' ')} limit {_fmt(limit)}"
    elif beyond and limits is not None:
        text += f"; the target is outside the {axis} range {_fmt(limits[0])}..{_fmt(limits[1])}"
    result.text = head + text
    return result


def _settled(axis: str, samples: list[Sample]) -> bool:
    """The last samples span SETTLED_S or more without the angle changing."""
    last = samples[-1]
    for s in reversed(samples):
        if abs(difference(axis, s.value(axis), last.value(axis))) >= STILL_DEG:
            return False
        if last.time - s.time >= SETTLED_S:
            return True
    return False


def _after(why: str) -> str:
    return why if why.startswith("within") else f"before {why}"
