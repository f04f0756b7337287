"""A stick movement judged: its commanded motion against the feedback, its cadence, the stop."""

from __future__ import annotations

import itertools
from typing import Any

from analyzer.analysis.findings import (
    CHECK_RATE,
    CHECK_REPEAT,
    CHECK_STOP,
    NOT_OBEYED,
    OBEYED,
    PARTIAL,
    UNKNOWN,
    Finding,
    worst,
)
from analyzer.analysis.motion_fit import AxisFit, CommandedMotion, fit
from analyzer.analysis.samples import MOTOR_YAW, PITCH, Sample
from analyzer.analysis.streams import HOLD_S, RECOMMENDED_REPEAT_S, Movement

RATE_OK = (0.75, 1.33)  # measured / commanded motion within this range: obeyed
RATE_NONE = 0.1  # below this (or negative): it did not follow
LATE_S = 0.25  # a lag this long is said
NAME = "gimbal_control"
# (word, feedback axis, index in the commanded motion, finding key)
AXES = (("pan", MOTOR_YAW, 0, "pan"), ("tilt", PITCH, 1, "tilt"))
_SENT_ONCE = (
    "sent once, not repeated: the gimbal stops when the commands stop "
    f"(the document recommends repeating every {RECOMMENDED_REPEAT_S * 1000:.0f} ms)"
)


def judge_movement(
    movement: Movement, before: Sample | None, inside: list[Sample], min_motion: float
) -> Finding:
    """The movement's commanded motion against the motion the feedback shows.

    ``before`` is the last attitude sample before the movement, ``inside`` those up to
    its window's end; an axis counts as commanded when the commands asked it to turn by
    more than ``min_motion`` degrees (the tolerance; both ways counted)."""
    end = movement.end if movement.end is not None else movement.last + HOLD_S
    motion = CommandedMotion(movement.commands, HOLD_S)
    asked = motion.at(end)
    duration = max(end - movement.start, 1e-9)
    path = motion.path(movement.start, end)
    extra: dict[str, Any] = {
        "component": movement.component,
        "command_count": movement.count,
        "duration_s": end - movement.start,
        "interval_mean_s": movement.interval_mean,
        "interval_max_s": movement.interval_max if movement.count > 1 else None,
    }
    # A message whose segments came late is dated after it measured: left out of the fit.
    points = [s for s in ([before] if before is not None else []) + inside if not s.late]
    series: dict[int, list[tuple[float, float]]] = {}
    limits: dict[int, float | None] = {}
    commanded: list[tuple[str, str, int, str]] = []
    for word, axis, index, key in AXES:
        if path[index] <= min_motion:
            continue
        commanded.append((word, axis, index, key))
        extra[f"commanded_{key}_dps"] = asked[index] / duration
        extra[f"peak_{key}_dps"] = movement.peak_pan if index == 0 else movement.peak_tilt
        usable, limits[index] = _until_limit(points, axis)
        series[index] = [(s.time, s.value(axis)) for s in usable]
    if points:
        extra["observed_at"] = points[-1].time
    if not commanded:
        text = (
            f"too little commanded motion to measure: {max(path):.1f} deg over "
            f"{end - movement.start:.1f} s (no more than the {min_motion:g} deg tolerance)"
        )
        return Finding(NAME, movement.start, CHECK_RATE, UNKNOWN, text, extra)
    found = fit(motion, {i: p for i, p in series.items() if len(p) >= 2})
    verdicts: list[str] = []
    texts: list[str] = []
    ratios: list[float] = []
    for word, _, index, key in commanded:
        axis_fit = found.axes.get(index) if found is not None else None
        limit = limits[index]
        if axis_fit is None:
            if limit is not None:
                verdicts.append(OBEYED)
                texts.append(f"{word} turned until its limit {limit:.1f}")
            else:
                verdicts.append(UNKNOWN)
                texts.append(f"{word} not measurable: {_too_few(movement, len(series[index]))}")
            continue
        verdict, said = _axis_verdict(word, axis_fit)
        ratios.append(axis_fit.ratio)
        extra[f"{key}_ratio"] = axis_fit.ratio
        extra[f"measured_{key}_dps"] = axis_fit.ratio * asked[index] / duration + 0.0
        if limit is not None:
            said += f", then at its limit {limit:.1f}"
        verdicts.append(verdict)
        texts.append(said)
    if ratios:
        extra["rate_ratio"] = max(ratios, key=lambda r: abs(1 - r))
    if found is not None and found.lag_measured and any(abs(r) >= RATE_NONE for r in ratios):
        extra["lag_s"] = found.lag_s
        if found.lag_s >= LATE_S:
            texts.append(f"it followed about {found.lag_s:.1f} s late")
    if movement.cut_short and UNKNOWN in verdicts:
        texts.append(f"until {movement.cut_short}")
    verdict = worst(*verdicts)
    return Finding(NAME, movement.start, CHECK_RATE, verdict, "; ".join(texts), extra)


def _until_limit(points: list[Sample], axis: str) -> tuple[list[Sample], float | None]:
    """The samples before the first one at a limit of ``axis``, and that limit."""
    for n, s in enumerate(points):
        limit = s.at_limit(axis)
        if limit is not None:
            return points[:n], limit
    return points, None


def _too_few(movement: Movement, count: int) -> str:
    what = f"{count} attitude message{'s' if count != 1 else ''} from just before it"
    until = f"until {movement.cut_short}" if movement.cut_short else "to after it"
    return f"{what} {until} (two are needed)"


def _axis_verdict(word: str, axis_fit: AxisFit) -> tuple[str, str]:
    ratio = axis_fit.ratio
    said = (
        f"{word} turned {axis_fit.measured_deg:.1f} deg for {axis_fit.commanded_deg:.1f} "
        f"commanded ({ratio * 100:.0f} % by the fit over {axis_fit.intervals} feedback "
        f"interval{'s' if axis_fit.intervals != 1 else ''})"
    )
    if ratio < 0:
        return NOT_OBEYED, said + ", the wrong way"
    if ratio < RATE_NONE:
        return NOT_OBEYED, said + ", it hardly moved"
    if ratio < RATE_OK[0]:
        return PARTIAL, said + ", sluggish"
    if ratio > RATE_OK[1]:
        return PARTIAL, said + ", too fast"
    return OBEYED, said


def judge_stop(name: str, end: float, after: list[Sample], tolerance: float) -> Finding | None:
    """Still moving after the stick came back (``end``)? None when too few samples show it."""
    if len(after) < 2:
        return None
    first = after[0]
    moved_at = None
    moved = 0.0
    for prev, s in itertools.pairwise(after):
        for axis in (PITCH, MOTOR_YAW):
            total = abs(s.value(axis) - first.value(axis))
            if abs(s.value(axis) - prev.value(axis)) > 0.05:
                moved_at = s.time
            moved = max(moved, total)
    extra: dict[str, Any] = {"moved_deg": moved, "observed_at": after[-1].time}
    if moved <= tolerance or moved_at is None:
        extra["duration_s"] = after[-1].time - end
        text = f"stopped when the commands stopped (still for {after[-1].time - end:.1f} s)"
        return Finding(name, end, CHECK_STOP, OBEYED, text, extra)
    still = moved_at - end
    extra["duration_s"] = still
    text = f"still moving {still:.1f} s after the commands stopped (moved {moved:.1f} deg more)"
    if moved_at >= after[-1].time:
        text = (
            f"still moving {still:.1f} s after the commands stopped, and still moving "
            f"(moved {moved:.1f} deg more)"
        )
    return Finding(name, end, CHECK_STOP, NOT_OBEYED, text, extra)


def judge_cadence(movement: Movement, rate_verdict: str) -> Finding | None:
    """The stream repeated too slowly to keep the gimbal moving: said once per stream, at
    the first movement it shows in (None when fast enough, or said already)."""
    stream = movement.stream
    if stream.cadence_said or not movement.too_slow():
        return None
    stream.cadence_said = True
    verdict = OBEYED if rate_verdict == OBEYED else PARTIAL
    extra: dict[str, Any] = {
        "component": movement.component,
        "command_count": movement.count,
        "interval_mean_s": movement.interval_mean,
        "interval_max_s": movement.interval_max if movement.count > 1 else None,
    }
    mean = movement.interval_mean
    if mean is None:
        return Finding(NAME, movement.start, CHECK_REPEAT, verdict, _SENT_ONCE, extra)
    text = (
        f"repeated every {mean:.2f} s on average (longest pause {movement.interval_max:.2f} s) "
        f"while the stick was off centre; the document recommends "
        f"{RECOMMENDED_REPEAT_S * 1000:.0f} ms to keep it moving"
    )
    return Finding(NAME, movement.start, CHECK_REPEAT, verdict, text, extra)
