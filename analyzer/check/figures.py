"""Motion figures from attitude samples: latency, slew, overshoot, settle, rate, feedback."""

from __future__ import annotations

import itertools
import statistics
from dataclasses import dataclass

from analyzer.analysis.samples import YAW, Sample
from analyzer.analysis.yaw_geometry import angle_error, shortest_difference

MIN_MOVING_SAMPLES = 2  # a slope needs two samples in the moving part
MIN_RATE_SPAN_S = 0.4  # samples used for a rate must span at least this long


def unwrapped(axis: str, start: float, value: float) -> float:
    """``value`` on a line through ``start``: yaw from north is taken the short way round."""
    if axis == YAW:
        return start + shortest_difference(value, start)
    return value


def slope(points: list[tuple[float, float]]) -> float | None:
    """Least-squares slope of (time, value) points; None for fewer than two distinct times."""
    if len(points) < 2:
        return None
    mean_t = sum(t for t, _ in points) / len(points)
    mean_v = sum(v for _, v in points) / len(points)
    den = sum((t - mean_t) ** 2 for t, _ in points)
    if den <= 0:
        return None
    return sum((t - mean_t) * (v - mean_v) for t, v in points) / den


@dataclass(frozen=True)
class MoveFigures:
    """How a move to an angle went, measured on one axis."""

    latency_s: float | None
    slew_dps: float | None
    overshoot_deg: float | None
    settle_s: float | None
    error_deg: float | None
    moving_samples: int

    def as_dict(self) -> dict[str, float]:
        names = ("latency_s", "slew_dps", "overshoot_deg", "settle_s", "error_deg")
        return {n: v for n in names if (v := getattr(self, n)) is not None}


def move_figures(
    axis: str,
    target: float,
    command_time: float,
    before: Sample | None,
    samples: list[Sample],
    tolerance: float,
) -> MoveFigures:
    """Figures of a move toward ``target`` on ``axis`` from the samples after the command.

    The settling time and the final error are given only once the gimbal has come to
    rest (two samples in a row within the tolerance). The slew rate is the slope fitted
    to the samples in the moving part only (neither within the tolerance of the start
    nor of the end), so the time the command took to act and the time spent still at
    the end do not lower it. The latency is extrapolated back from the first sample in
    motion at that slew rate.
    """
    if not samples:
        return MoveFigures(None, None, None, None, None, 0)
    start = (before or samples[0]).value(axis)
    values = [unwrapped(axis, start, s.value(axis)) for s in samples]
    final = values[-1]
    goal = unwrapped(axis, start, target)
    error: float | None = angle_error(axis, target, samples[-1])
    settled_at = len(values) - 1
    while settled_at > 0 and abs(values[settled_at - 1] - final) <= tolerance:
        settled_at -= 1
    # Settled: at least the last two samples within the tolerance of each other. A gimbal
    # still on its way at the last sample has no settling time and no final error.
    settled = settled_at < len(values) - 1
    moved = abs(final - start) > tolerance
    settle = samples[settled_at].time - command_time if settled and moved else None
    if not settled:
        error = None
    # Without a sample from before the command the first one may already be under way.
    moving = [
        (s.time, v)
        for s, v in zip(samples[:settled_at], values[:settled_at], strict=True)
        if before is None or abs(v - start) > tolerance
    ]
    rate = slope(moving) if len(moving) >= MIN_MOVING_SAMPLES else None
    slew = abs(rate) if rate is not None else None
    latency = None
    if rate and moving and before is not None:
        first_time, first_value = moving[0]
        latency = (first_time - command_time) - abs(first_value - start) / abs(rate)
        latency = min(max(0.0, latency), first_time - command_time)
    direction = 1.0 if goal >= start else -1.0
    overshoot = max(0.0, *(direction * (v - goal) for v in values))
    return MoveFigures(latency, slew, overshoot, settle, error, len(moving))


def rate_figure(axis: str, samples: list[Sample], tolerance: float) -> float | None:
    """The rate (deg/s, signed) of ``axis`` over ``samples`` taken while commands asked for a
    speed, from the first sample that moved on (before it the gimbal had not started)."""
    if len(samples) < 2:
        return None
    start = samples[0].value(axis)
    points = [(s.time, unwrapped(axis, start, s.value(axis))) for s in samples]
    first = next((i for i, (_, v) in enumerate(points) if abs(v - start) > tolerance / 4), None)
    if first is None:
        return slope(points)  # it never moved: the slope says so (about 0)
    moving = points[max(0, first - 1) :] if first > 1 else points
    if moving[-1][0] - moving[0][0] < MIN_RATE_SPAN_S:
        return None
    return slope(moving)


@dataclass(frozen=True)
class FeedbackFigures:
    """The feedback rhythm over a listening window."""

    messages: int
    period_s: float | None
    lost: int
    crc_errors: int
    longest_gap_s: float

    def as_dict(self) -> dict[str, float | int]:
        out: dict[str, float | int] = {
            "messages": self.messages,
            "lost": self.lost,
            "crc_errors": self.crc_errors,
        }
        if self.period_s is not None:
            out["period_s"] = self.period_s
        return out


def feedback_figures(
    times: list[float], damaged: int, start: float, end: float, period: float
) -> FeedbackFigures:
    """Feedback message times inside [start, end] -> median period and messages lost.

    Messages are lost when the span from the first to the last holds more of them at the
    nominal ``period`` than arrived; a silence at either end of the window counts too.
    """
    inside = sorted(t for t in times if start <= t <= end)
    gaps = [b - a for a, b in itertools.pairwise(inside)]
    edges = [inside[0] - start, end - inside[-1]] if inside else [end - start]
    if inside:
        # Counted over the whole span, so two messages read late together (one TCP read)
        # are not a loss: only fewer messages than the span holds are.
        lost = max(0, round((inside[-1] - inside[0]) / period) + 1 - len(inside))
        lost += sum(max(0, int(edge / period + 0.5) - 1) for edge in edges)
    else:  # every message the window should have held
        lost = int((end - start) / period)
    median = statistics.median(gaps) if gaps else None
    longest = max([*gaps, *edges]) if inside else end - start
    return FeedbackFigures(len(inside), median, lost, damaged, longest)


def longest_silence(times: list[float], start: float, end: float) -> tuple[float, float]:
    """(length, start time) of the longest stretch of [start, end] without a message."""
    inside = sorted(t for t in times if start <= t <= end)
    marks = [start, *inside, end]
    best = (0.0, start)
    for a, b in itertools.pairwise(marks):
        if b - a > best[0]:
            best = (b - a, a)
    return best
