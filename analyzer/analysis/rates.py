"""A stick movement judged: its commanded motion against the feedback, its cadence, the stop."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from typing import Any

from analyzer.analysis.findings import (
    CHECK_RATE,
    CHECK_REPEAT,
    CHECK_STOP,
    NOT_OBEYED,
    OBEYED,
    PARTIAL,
    UNKNOWN,
    ResponseFinding,
    worst,
)
from analyzer.analysis.motion_fit import (
    LAG_MAX_S,
    MIN_INTERVALS,
    AxisFit,
    CommandedMotion,
    Fit,
    fit,
    whole,
)
from analyzer.analysis.samples import MOTOR_YAW, PITCH, Sample
from analyzer.analysis.streams import HOLD_S, RECOMMENDED_REPEAT_S, EndedBy, Movement
from analyzer.analysis.targets import STILL_DEG

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


class CutBy(Enum):
    """What ended the feedback before a movement's window was over (its value: the words)."""

    INPUT_ENDED = "the input ended"
    FEEDBACK_STOPPED = "the feedback stopped"

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class Cut:
    """The feedback ended before a movement's window was over: ``what`` ended it and
    ``at`` what time."""

    what: CutBy
    at: float


@dataclass(frozen=True)
class MovementVerdict:
    """A movement's finding, and how the gimbal followed while the stick was off centre
    (lag, ratio per axis; None when no fit): what the stop check takes as explained."""

    finding: ResponseFinding
    followed: tuple[float, dict[int, float]] | None


@dataclass
class _Asked:
    """What a movement's commands asked of each axis that turned more than the tolerance,
    and the feedback to measure it by (up to an axis' limit)."""

    motion: CommandedMotion
    asked: list[float]
    duration: float
    points: list[Sample]
    series: dict[int, list[tuple[float, float]]]
    limits: dict[int, float | None]
    commanded: list[tuple[str, str, int, str]]


def judge_movement(
    movement: Movement,
    before: Sample | None,
    inside: list[Sample],
    min_motion: float,
    *,
    free_from: float | None = None,
    cut: Cut | None = None,
) -> MovementVerdict:
    """The movement's commanded motion against the motion the feedback shows.

    ``before`` is the last attitude sample before the movement, ``inside`` those up to
    its window's end; an axis counts as commanded when the commands asked it to turn by
    more than ``min_motion`` degrees (the tolerance; both ways counted). ``free_from``:
    another command may have been turning the gimbal until the movement's start (what
    it did before the start plus the lag is left out). ``cut``: the feedback ended before
    the window did; unless what came shows the movement's motion over (past its lag),
    it is ``unknown``."""
    end = movement.end if movement.end is not None else movement.last + HOLD_S
    extra: dict[str, Any] = {
        "component": movement.component,
        "command_count": movement.count,
        "duration_s": end - movement.start,
        "interval_mean_s": movement.interval_mean,
        "interval_max_s": movement.interval_max if movement.count > 1 else None,
    }
    asked = _asked(movement, before, inside, min_motion, end, extra)
    if not asked.commanded:
        path = asked.motion.path(movement.start, end)
        text = (
            f"too little commanded motion to measure: {max(path):.1f} deg over "
            f"{end - movement.start:.1f} s (no more than the {min_motion:g} deg tolerance)"
        )
        finding = ResponseFinding(NAME, movement.start, CHECK_RATE, UNKNOWN, text, extra)
        return MovementVerdict(finding, None)
    motion, points = asked.motion, asked.points
    measured = {i: p for i, p in asked.series.items() if len(p) >= 2}
    found = fit(motion, measured, free_from=free_from, free_until=movement.free_until)
    if found is None and _seen_whole(movement, before, points, free_from, end):
        found = whole(motion, measured)
    lag = found.lag_s if found is not None and found.lag_measured else LAG_MAX_S
    # ``end`` is when the commands stopped asking for motion (a 0, 0 command, or the last
    # one's hold): a gimbal ``lag`` late has done with the movement then.
    if cut is not None and (not points or points[-1].time < end + lag):
        text = f"{_cut_words(movement, cut, end)}: the motion it asked for cannot be judged"
        finding = ResponseFinding(NAME, movement.start, CHECK_RATE, UNKNOWN, text, extra)
        return MovementVerdict(finding, None)
    verdicts, texts, ratios = _axis_verdicts(movement, asked, found, free_from, extra)
    if ratios:
        extra["rate_ratio"] = max(ratios, key=lambda r: abs(1 - r))
    # How it followed while the stick was off centre, and not after (a gimbal that
    # drifts on would pass for a late one): what the stop check takes as explained.
    onset = fit(
        motion, measured, free_from=free_from, free_until=movement.free_until, seen_until=end
    )
    followed = None
    if onset is not None:
        followed = (onset.lag_s, {i: a.ratio for i, a in onset.axes.items()})
    if found is not None and found.lag_measured and any(abs(r) >= RATE_NONE for r in ratios):
        extra["lag_s"] = found.lag_s
        if found.lag_s >= LATE_S:
            texts.append(f"it followed about {found.lag_s:.1f} s late")
    verdict = worst(*verdicts)
    finding = ResponseFinding(NAME, movement.start, CHECK_RATE, verdict, "; ".join(texts), extra)
    return MovementVerdict(finding, followed)


def _asked(
    movement: Movement,
    before: Sample | None,
    inside: list[Sample],
    min_motion: float,
    end: float,
    extra: dict[str, Any],
) -> _Asked:
    """What the movement asked of each axis, and the feedback of each commanded one."""
    motion = movement.motion()
    at_start = motion.at(movement.start)
    asked = [a - b for a, b in zip(motion.at(end), at_start, strict=True)]
    duration = max(end - movement.start, 1e-9)
    path = motion.path(movement.start, end)
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
        usable, limits[index] = _until_limit(points, axis, asked[index])
        series[index] = [(s.time, s.value(axis)) for s in usable]
    if points:
        extra["observed_at"] = points[-1].time
    return _Asked(motion, asked, duration, points, series, limits, commanded)


def _axis_verdicts(
    movement: Movement,
    asked: _Asked,
    found: Fit | None,
    free_from: float | None,
    extra: dict[str, Any],
) -> tuple[list[str], list[str], list[float]]:
    """Each commanded axis' verdict, its words and the ratio measured (where it was)."""
    verdicts: list[str] = []
    texts: list[str] = []
    ratios: list[float] = []
    whole_movement = found is not None and not found.lag_measured
    for word, _, index, key in asked.commanded:
        axis_fit = found.axes.get(index) if found is not None else None
        limit = asked.limits[index]
        if axis_fit is None:
            verdict, said = _unmeasured(word, limit, asked.asked[index], movement, free_from)
            verdicts.append(verdict)
            texts.append(said)
            continue
        verdict, said = _axis_verdict(word, axis_fit, whole_movement=whole_movement)
        ratios.append(axis_fit.ratio)
        extra[f"{key}_ratio"] = axis_fit.ratio
        extra[f"measured_{key}_dps"] = axis_fit.ratio * asked.asked[index] / asked.duration + 0.0
        if limit is not None:
            said += f", then at its limit {limit:.1f}"
        verdicts.append(verdict)
        texts.append(said)
    return verdicts, texts, ratios


def _unmeasured(
    word: str, limit: float | None, asked: float, movement: Movement, free_from: float | None
) -> tuple[str, str]:
    """An axis the fit could not measure: at its limit the way it was asked, the wrong
    way, or unknown."""
    if limit is not None and limit * asked > 0:
        return OBEYED, f"{word} turned until its limit {limit:.1f}"
    if limit is not None:  # the stop on the other side: it turned the wrong way
        return NOT_OBEYED, f"{word} turned to its limit {limit:.1f}, the wrong way"
    return UNKNOWN, f"{word} not measurable: {_too_few(movement, free_from)}"


def _seen_whole(
    movement: Movement,
    before: Sample | None,
    points: list[Sample],
    free_from: float | None,
    end: float,
) -> bool:
    """The feedback saw the whole movement and nothing else: the gimbal free of other
    commands and of the stream's earlier speeds before it, a message before its start,
    and the last one past its longest lag, before another command or the stream's next
    movement asked for more."""
    if before is None or free_from is not None or not points or points[0] is not before:
        return False
    if any(c.pan or c.tilt for c in movement.prior):
        return False
    last = points[-1].time
    more = [c.time for c in movement.commands if c.time > end and (c.pan or c.tilt)]
    if movement.free_until is not None:
        more.append(movement.free_until)
    return end + LAG_MAX_S <= last <= min(more, default=last)


def _cut_words(movement: Movement, cut: Cut, end: float) -> str:
    """'the input ended 0.4 s into the movement' or '... 0.6 s after it, before ...'."""
    if cut.at < movement.start:
        return f"{cut.what} {movement.start - cut.at:.1f} s before the movement"
    if movement.ended_by is EndedBy.INPUT_ENDED or cut.at < end:
        return f"{cut.what} {max(0.0, cut.at - movement.start):.1f} s into the movement"
    return (
        f"{cut.what} {cut.at - end:.1f} s after it, before its last motion could be seen "
        f"(a gimbal may follow up to {LAG_MAX_S:g} s late)"
    )


def _until_limit(
    points: list[Sample], axis: str, asked: float
) -> tuple[list[Sample], float | None]:
    """The samples before the first one at a limit of ``axis``, and that limit. A
    movement that starts at the stop opposite to where it was ``asked`` to turn (a check
    starts a long speed step there) leaves that stop: its first samples there are no end."""
    leaving = True
    for n, s in enumerate(points):
        limit = s.at_limit(axis)
        if limit is None:
            leaving = False
        elif not (leaving and limit * asked < 0):
            return points[:n], limit
    return points, None


def _too_few(movement: Movement, free_from: float | None) -> str:
    """Why too few feedback intervals measured an axis."""
    why = f"fewer than {MIN_INTERVALS} feedback intervals"
    if free_from is not None:
        why += f" after {movement.other_name} before it had done with the gimbal"
    if movement.cut_short:
        why += f", until {movement.cut_short}"
    return why + " (a lag cannot be told from a ratio), and the movement was not seen whole"


def _axis_verdict(word: str, axis_fit: AxisFit, *, whole_movement: bool) -> tuple[str, str]:
    ratio = axis_fit.ratio
    n = axis_fit.intervals
    how = "over the whole movement" if whole_movement else "by the fit"
    said = (
        f"{word} turned {axis_fit.measured_deg:.1f} deg for {axis_fit.commanded_deg:.1f} "
        f"commanded ({ratio * 100:.0f} % {how} over {n} feedback interval{'s' if n != 1 else ''})"
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


def judge_stop(
    name: str,
    end: float,
    after: list[Sample],
    tolerance: float,
    follows: Callable[[str, list[float]], list[float]] | None = None,
) -> ResponseFinding | None:
    """Still moving after the stick came back (``end``)? None when too few samples show it.

    ``follows(axis, times)``: the angles of ``axis`` at ``times`` that the movement's commands,
    followed late as its fit measured, still explain (a late gimbal finishes the
    movement after the stick came back); only motion on beyond that counts (stopping
    sooner than the fit says is no fault), by more than the tolerance and a quarter of
    what the fit explains (its lag and ratio are estimates)."""
    if len(after) < 2:
        return None

    times = [s.time for s in after]
    first = after[0]
    moved_at = None
    moved = 0.0
    for axis in (PITCH, MOTOR_YAW):
        explained = follows(axis, times) if follows is not None else [0.0] * len(after)
        expected = explained[-1] - explained[0]
        way = math.copysign(1.0, expected) if abs(expected) > STILL_DEG else 0.0
        beyond = 0.0
        for k in range(1, len(after)):
            prev, s = after[k - 1], after[k]
            step = (s.value(axis) - explained[k]) - (prev.value(axis) - explained[k - 1])
            if abs(step) > 0.05:
                moved_at = s.time if moved_at is None else max(moved_at, s.time)
            more = (s.value(axis) - first.value(axis)) - (explained[k] - explained[0])
            beyond = max(beyond, way * more if way else abs(more))
        if beyond > tolerance + 0.25 * abs(expected):
            moved = max(moved, beyond)
    extra: dict[str, Any] = {"moved_deg": moved, "observed_at": after[-1].time}
    if not moved or moved_at is None:
        extra["duration_s"] = after[-1].time - end
        text = f"stopped when the commands stopped (still for {after[-1].time - end:.1f} s)"
        return ResponseFinding(name, end, CHECK_STOP, OBEYED, text, extra)
    still = moved_at - end
    extra["duration_s"] = still
    text = f"still moving {still:.1f} s after the commands stopped (moved {moved:.1f} deg more)"
    if moved_at >= after[-1].time:
        text = (
            f"still moving {still:.1f} s after the commands stopped, and still moving "
            f"(moved {moved:.1f} deg more)"
        )
    return ResponseFinding(name, end, CHECK_STOP, NOT_OBEYED, text, extra)


def judge_cadence(movement: Movement, rate_verdict: str) -> ResponseFinding | None:
    """The stream repeated too slowly to keep the gimbal moving: said once per stream, at
    the first movement it shows in (None when fast enough, or said already: the caller
    records that it was said)."""
    said = movement.stream.cadence_said
    if said or movement.ended_by is EndedBy.INPUT_ENDED or not movement.too_slow():
        return None  # (the input ended: what would have followed is not known)
    verdict = OBEYED if rate_verdict == OBEYED else PARTIAL
    extra: dict[str, Any] = {
        "component": movement.component,
        "command_count": movement.count,
        "interval_mean_s": movement.interval_mean,
        "interval_max_s": movement.interval_max if movement.count > 1 else None,
    }
    mean = movement.interval_mean
    if mean is None:
        return ResponseFinding(NAME, movement.start, CHECK_REPEAT, verdict, _SENT_ONCE, extra)
    text = (
        f"repeated every {mean:.2f} s on average (longest pause {movement.interval_max:.2f} s) "
        f"while the stick was off centre; the document recommends "
        f"{RECOMMENDED_REPEAT_S * 1000:.0f} ms to keep it moving"
    )
    return ResponseFinding(NAME, movement.start, CHECK_REPEAT, verdict, text, extra)
