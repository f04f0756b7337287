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
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

LAG_STEP_S = 0.05  # the lag search grid: 0, 50 ms, ... LAG_MAX_S
LAG_MAX_S = 1.0
LAGS = tuple(round(i * LAG_STEP_S, 3) for i in range(round(LAG_MAX_S / LAG_STEP_S) + 1))
_TIE = 1e-9  # residuals this close are a tie: the shorter lag wins
# Fewer feedback intervals than this cannot tell a lag from a ratio: the lag is not
# searched (taken as 0), and the fit says it was not measured.
MIN_INTERVALS_FOR_LAG = 3

Floats = npt.NDArray[np.float64]


@dataclass(slots=True)
class Command:
    """Speeds (deg/s) asked from ``time`` on (never changed once made; not frozen, which
    would cost every gimbal_control of a log a third of a microsecond more)."""

    time: float
    pan: float
    tilt: float


class CommandedMotion:
    """The angles the commands ask for, integrated from the first command: each command's
    speeds hold until the next command, or for ``hold`` seconds when the next one comes
    later than that (the gimbal stops when the commands stop)."""

    def __init__(self, commands: Sequence[Command], hold: float) -> None:
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
    ``lag_measured`` is False when too few intervals allowed no search (lag 0)."""

    lag_s: float
    axes: dict[int, AxisFit]  # 0 = pan, 1 = tilt
    lag_measured: bool = True


def fit(
    motion: CommandedMotion,
    samples: dict[int, Sequence[tuple[float, float]]],
    lags: Sequence[float] = LAGS,
) -> Fit | None:
    """The least-squares fit of the measured angles ``samples`` (axis -> (time, angle),
    oldest first; 0 = pan, 1 = tilt) to ``motion`` over the lags of ``lags``.

    None when no axis has two samples with commanded motion between them (at every lag).
    With fewer than MIN_INTERVALS_FOR_LAG intervals on every axis only lag 0 is tried."""
    searched = max((len(p) - 1 for p in samples.values()), default=0) >= MIN_INTERVALS_FOR_LAG
    grid = np.array(lags if searched else (0.0,), dtype=np.float64)
    residual = np.zeros(len(grid))
    usable = np.ones(len(grid), dtype=bool)
    sums: dict[int, tuple[Floats, Floats, Floats]] = {}
    for axis, points in samples.items():
        if len(points) < 2:
            continue
        times = np.array([t for t, _ in points], dtype=np.float64)
        measured = np.diff(np.array([v for _, v in points], dtype=np.float64))
        asked = motion.axis_at((times[None, :] - grid[:, None]).ravel(), axis)
        asked = asked.reshape(len(grid), len(times))
        steps = np.diff(asked, axis=1)
        s_cc = (steps * steps).sum(axis=1)
        s_mc = (steps * measured[None, :]).sum(axis=1)
        fitted = s_cc > 1e-12
        usable &= fitted
        ratio = np.where(fitted, s_mc / np.where(fitted, s_cc, 1.0), 0.0)
        residual += float((measured * measured).sum()) - s_mc * ratio
        sums[axis] = (ratio, asked[:, -1] - asked[:, 0], np.full(len(grid), measured.sum()))
    if not sums or not usable.any():
        return None
    candidates = np.where(usable, residual, np.inf)
    best = int(np.flatnonzero(candidates <= candidates.min() + _TIE)[0])
    axes = {
        axis: AxisFit(
            float(ratio[best]),
            float(commanded[best]),
            float(measured[best]),
            len(samples[axis]) - 1,
        )
        for axis, (ratio, commanded, measured) in sums.items()
    }
    return Fit(float(grid[best]), axes, searched)
