"""Commanded speeds against measured angles: the ratio and lag that fit a movement best.

A pilot's stick changes the speeds in every command, so no two commands are "the same
speed repeated" and no single rate can be measured. What can be measured is motion: the
commanded speeds integrated over time give the angle the commands asked the gimbal to
turn by; the feedback (every 0.5 s) gives the angle it did turn by. Over each interval
between two feedback messages the measured change is compared with the commanded change
``lag`` seconds earlier, and the ratio that fits best in the least-squares sense is the
gimbal's answer to the stick; the lag is the one, of a search grid, that leaves the least
residual. The commanded motion is piecewise linear (a speed held between two times), so
it is kept as its corners and read off with ``numpy.interp`` at every lag at once.

Only intervals the commands alone can explain are fitted: when something else may have
been turning the gimbal before the movement (another command), or takes it over after
(the next command), the intervals before ``free_from`` plus the lag, and after
``free_until`` plus the lag, are left out, lag by lag. The lag cannot be told from the
ratio with fewer than MIN_INTERVALS intervals; then only a movement seen whole (the
gimbal free before it and the feedback on past its longest lag) is measured, by its
whole change, which no lag alters (``whole``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

LAG_STEP_S = 0.05  # the lag search grid: 0, 50 ms, ... LAG_MAX_S
LAG_MAX_S = 1.0
LAGS = tuple(round(i * LAG_STEP_S, 3) for i in range(round(LAG_MAX_S / LAG_STEP_S) + 1))
_TIE = 1e-9  # residuals this close are a tie: the shorter lag wins
# Fewer feedback intervals than this, each with commanded or measured motion (INFORMATIVE
# of the most in one interval), cannot tell a lag from a ratio: no fit is made.
MIN_INTERVALS = 3
INFORMATIVE = 0.1

Floats = npt.NDArray[np.float64]


@dataclass(slots=True)
class StickCommand:
    """Speeds (deg/s) asked from ``time`` on (never changed once made; not frozen, which
    would cost every gimbal_control of a log a third of a microsecond more)."""

    time: float
    pan: float
    tilt: float


class CommandedMotion:
    """The angles the commands ask for, integrated from the first command: each command's
    speeds hold until the next command, or for ``hold`` seconds when the next one comes
    later than that (the gimbal stops when the commands stop)."""

    def __init__(self, commands: Sequence[StickCommand], hold: float) -> None:
        # Two corners a command: where it starts, and where its speeds stop holding.
        start = np.array([c.time for c in commands], dtype=np.float64)
        until = start + hold
        until[:-1] = np.minimum(until[:-1], start[1:])
        span = np.maximum(0.0, until - start)
        self.times: Floats = np.empty(2 * len(start), dtype=np.float64)
        self.times[0::2] = start
        self.times[1::2] = np.maximum(until, start)
        axes = []
        for speeds in ([c.pan for c in commands], [c.tilt for c in commands]):
            # cumsum adds in order, as a running total would: the same floats.
            after = np.cumsum(np.array(speeds, dtype=np.float64) * span)
            corners = np.empty(2 * len(start), dtype=np.float64)
            corners[1::2] = after
            corners[0:1] = 0.0
            corners[2::2] = after[:-1]
            axes.append(corners)
        self._axes: tuple[Floats, Floats] = (axes[0], axes[1])

    def at(self, t: float) -> tuple[float, float]:
        """(pan, tilt) degrees asked from the first command up to ``t``."""
        pan, tilt = (float(self.axis_at(np.array([t]), axis)[0]) for axis in (0, 1))
        return pan, tilt

    def axis_at(self, t: Floats, axis: int) -> Floats:
        """Degrees asked of ``axis`` (0 pan, 1 tilt) up to each time of ``t``."""
        if not len(self.times):
            return np.zeros_like(t)
        return np.interp(t, self.times, self._axes[axis])

    def path(self, start: float, end: float) -> tuple[float, float]:
        """How far each axis was asked to turn between ``start`` and ``end``, counting
        both directions (the length of the way, not the net change)."""
        inside = self.times[(self.times > start) & (self.times < end)]
        points = np.concatenate(([start], inside, [end]))
        pan, tilt = (float(np.abs(np.diff(self.axis_at(points, a))).sum()) for a in (0, 1))
        return pan, tilt


@dataclass(frozen=True, slots=True)
class AxisFit:
    """One axis' best fit: measured change over commanded change, and both sizes."""

    ratio: float
    commanded_deg: float  # the commanded change over the intervals used, signs kept
    measured_deg: float
    intervals: int


@dataclass(frozen=True, slots=True)
class Fit:
    """The lag that fits every fitted axis best, and each axis' fit at that lag;
    ``lag_measured`` is False for a movement measured whole (``whole``: no lag)."""

    lag_s: float
    axes: dict[int, AxisFit]  # 0 = pan, 1 = tilt
    lag_measured: bool = True


def fit(
    motion: CommandedMotion,
    samples: Mapping[int, Sequence[tuple[float, float]]],
    lags: Sequence[float] = LAGS,
    *,
    free_from: float | None = None,
    free_until: float | None = None,
    seen_until: float | None = None,
) -> Fit | None:
    """The least-squares fit of the measured angles ``samples`` (axis -> (time, angle),
    oldest first; 0 = pan, 1 = tilt) to ``motion`` over the lags of ``lags``.

    At a lag L an interval counts when it starts at or after ``free_from`` + L, ends at
    or before ``free_until`` + L and at or before ``seen_until`` (None: no bound). The
    lags are compared only when at every one of them every axis has MIN_INTERVALS
    intervals that count with commanded or measured motion in them (else a lag that
    spreads the motion over more intervals would win by having them); the best is the
    one with the least residual per interval. None when some lag cannot be tested."""
    grid = np.array(lags, dtype=np.float64)
    residual = np.zeros(len(grid))
    used = np.zeros(len(grid))
    usable = np.ones(len(grid), dtype=bool)
    sums: dict[int, tuple[Floats, Floats, Floats, npt.NDArray[np.int64]]] = {}
    for axis, points in samples.items():
        if len(points) < 2:
            continue
        times = np.array([t for t, _ in points], dtype=np.float64)
        measured = np.diff(np.array([v for _, v in points], dtype=np.float64))
        asked = motion.axis_at((times[None, :] - grid[:, None]).ravel(), axis)
        steps = np.diff(asked.reshape(len(grid), len(times)), axis=1)
        counts = np.ones_like(steps, dtype=bool)
        if free_from is not None:
            counts &= times[None, :-1] >= free_from + grid[:, None] - 1e-9
        if free_until is not None:
            counts &= times[None, 1:] <= free_until + grid[:, None] + 1e-9
        if seen_until is not None:  # at every lag alike
            counts &= times[None, 1:] <= seen_until + 1e-9
        steps = np.where(counts, steps, 0.0)
        kept = np.where(counts, measured[None, :], 0.0)
        s_cc = (steps * steps).sum(axis=1)
        s_mc = (steps * kept).sum(axis=1)
        number = counts.sum(axis=1)
        # An interval in which neither the commands nor the gimbal turned says nothing of
        # the ratio: with one that moved and two still, any lag fits perfectly.
        asked_in = np.abs(steps) >= INFORMATIVE * np.abs(steps).max(axis=1, keepdims=True)
        asked_in &= np.abs(steps) > 1e-9
        moved = np.abs(measured)
        moved_in = (moved >= INFORMATIVE * moved.max()) & (moved > 1e-9)
        informative = ((asked_in | moved_in[None, :]) & counts).sum(axis=1)
        fitted = (s_cc > 1e-12) & (informative >= MIN_INTERVALS)
        usable &= fitted
        ratio = np.where(fitted, s_mc / np.where(fitted, s_cc, 1.0), 0.0)
        residual += (kept * kept).sum(axis=1) - s_mc * ratio
        used += number
        sums[axis] = (ratio, steps.sum(axis=1), kept.sum(axis=1), number)
    if not sums or not usable.all():  # every lag must be testable, or none is compared
        return None
    candidates = residual / np.maximum(used, 1.0)
    best = int(np.flatnonzero(candidates <= candidates.min() + _TIE)[0])
    axes = {
        axis: AxisFit(float(ratio[best]), float(commanded[best]), float(got[best]), int(n[best]))
        for axis, (ratio, commanded, got, n) in sums.items()
    }
    return Fit(float(grid[best]), axes, len(grid) > 1)


def whole(
    motion: CommandedMotion, samples: Mapping[int, Sequence[tuple[float, float]]]
) -> Fit | None:
    """Each axis' whole change from its first sample to its last over the change the
    commands asked for in between: for a movement seen whole (the gimbal free before
    the first sample, the last one past the movement's longest lag), which no lag alters.
    None when an axis has fewer than two samples or no commanded change."""
    axes: dict[int, AxisFit] = {}
    for axis, points in samples.items():
        if len(points) < 2:
            return None
        (t0, v0), (t1, v1) = points[0], points[-1]
        start, end = motion.axis_at(np.array([t0, t1]), axis)
        asked = float(end - start)
        if abs(asked) <= 1e-9:
            return None
        axes[axis] = AxisFit((v1 - v0) / asked, asked, v1 - v0, len(points) - 1)
    return Fit(0.0, axes, False) if axes else None
