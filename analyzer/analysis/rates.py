"""gimbal_control bursts: measured against commanded rate, stop when commands stop, repeats."""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
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
from analyzer.analysis.samples import MOTOR_YAW, PITCH, Sample

RECOMMENDED_REPEAT_S = 0.05  # chapter 2.1, 0x04: "50ms at a time is recommended"
SLOW_REPEAT_S = 2 * RECOMMENDED_REPEAT_S  # mean interval above this is "too slowly"
_SENT_ONCE = (
    "sent once, not repeated: the gimbal stops when the commands stop "
    f"(the document recommends repeating every {RECOMMENDED_REPEAT_S * 1000:.0f} ms)"
)
BURST_GAP_S = 1.0  # commands further apart than this are separate bursts
RATE_OK = (0.75, 1.33)  # measured / commanded within this range: obeyed
RATE_NONE = 0.1  # below this (or negative): it did not follow
MIN_SPAN_S = 0.4  # the feedback used to measure a rate must span at least this long
_NOT_MEASURABLE = (
    f" not measurable: fewer than two feedback messages {MIN_SPAN_S:g} s apart while the "
    "commands lasted"
)
SAME_SPEED = 0.005  # deg/s: speeds that differ less are the same command repeated


@dataclass
class Burst:
    """gimbal_control commands with the same speeds, repeated without a long pause.

    Only what the judgements need is kept of the commands (first and last time, count,
    sum and longest of the intervals), so a burst held for an hour takes no more room."""

    name: str
    pan: float
    tilt: float
    start: float
    last: float = field(init=False)
    count: int = 1
    interval_sum: float = 0.0  # summed in order, as sum() of the intervals would be
    interval_max: float = 0.0
    stopped_at: float | None = None  # an explicit zero-speed command

    def __post_init__(self) -> None:
        self.last = self.start

    def add(self, t: float) -> None:
        """One more command of the burst, at ``t``."""
        interval = t - self.last
        self.interval_sum += interval
        self.interval_max = interval if self.count == 1 else max(self.interval_max, interval)
        self.count += 1
        self.last = t

    @property
    def end(self) -> float:
        """When the commands stopped: the explicit stop, else the last command."""
        return self.stopped_at if self.stopped_at is not None else self.last

    def same_speeds(self, pan: float, tilt: float) -> bool:
        return abs(pan - self.pan) < SAME_SPEED and abs(tilt - self.tilt) < SAME_SPEED


def _slope(samples: list[Sample], axis: str) -> float:
    n = len(samples)
    mean_t = sum(s.time for s in samples) / n
    mean_v = sum(s.value(axis) for s in samples) / n
    num = sum((s.time - mean_t) * (s.value(axis) - mean_v) for s in samples)
    den = sum((s.time - mean_t) ** 2 for s in samples)
    return num / den if den > 0 else 0.0


def _measure(
    burst: Burst, axis: str, before: Sample | None, inside: list[Sample]
) -> tuple[float | None, float | None, float | None]:
    """(measured rate, lag, limit reached) of one axis from the samples during the burst."""
    limit = None
    usable: list[Sample] = []
    for s in inside:
        limit = s.at_limit(axis)
        if limit is not None:
            break
        usable.append(s)
    if not usable:
        return None, None, limit
    if len(usable) < 2 or usable[-1].time - usable[0].time < MIN_SPAN_S:
        # One message cannot tell movement from lag; two close together (a late segment)
        # make the slope meaningless.
        return None, None, limit
    rate = _slope(usable, axis)
    lag = None
    if before is not None and abs(rate) > 1e-6 and len(usable) >= 2:
        moved = usable[-1].value(axis) - before.value(axis)
        span = usable[-1].time - burst.start
        lag = max(0.0, min(span, span - moved / rate))
    return rate, lag, limit


def judge_rate(burst: Burst, before: Sample | None, inside: list[Sample]) -> Finding:
    """Measured rate of each commanded axis against the commanded speed."""
    extra: dict[str, Any] = {
        "commanded_pan_dps": burst.pan,
        "commanded_tilt_dps": burst.tilt,
        "duration_s": burst.last - burst.start,
        "command_count": burst.count,
    }
    verdicts: list[str] = []
    texts: list[str] = []
    ratios: list[float] = []
    lags: list[float] = []
    for axis, word, commanded, key in (
        (MOTOR_YAW, "pan", burst.pan, "measured_pan_dps"),
        (PITCH, "tilt", burst.tilt, "measured_tilt_dps"),
    ):
        if abs(commanded) < SAME_SPEED:
            continue
        rate, lag, limit = _measure(burst, axis, before, inside)
        if rate is None:
            if limit is not None:
                verdicts.append(OBEYED)
                texts.append(f"{word} turned until its limit {limit:.1f}")
            else:
                verdicts.append(UNKNOWN)
                texts.append(f"{word}{_NOT_MEASURABLE}")
            continue
        extra[key] = rate
        ratio = rate / commanded
        ratios.append(ratio)
        if lag is not None:
            lags.append(lag)
        said = f"{word} {rate:.1f} deg/s for {commanded:.1f} commanded ({ratio * 100:.0f} %)"
        if ratio < 0:
            verdicts.append(NOT_OBEYED)
            said += ", the wrong way"
        elif ratio < RATE_NONE:
            verdicts.append(NOT_OBEYED)
            said += ", it hardly moved"
        elif ratio < RATE_OK[0]:
            verdicts.append(PARTIAL)
            said += ", sluggish"
        elif ratio > RATE_OK[1]:
            verdicts.append(PARTIAL)
            said += ", too fast"
        else:
            verdicts.append(OBEYED)
        if limit is not None:
            said += f", then at its limit {limit:.1f}"
        texts.append(said)
    if ratios:
        extra["rate_ratio"] = max(ratios, key=lambda r: abs(1 - r))
    if lags:
        extra["lag_s"] = max(lags)
        if max(lags) >= 0.25:
            texts.append(f"it started about {max(lags):.1f} s late")
    verdict = worst(*verdicts) if verdicts else UNKNOWN
    detail = "; ".join(texts) if texts else "no speed commanded"
    return Finding(burst.name, burst.start, CHECK_RATE, verdict, detail, extra)


def judge_stop(burst: Burst, after: list[Sample], tolerance: float) -> Finding | None:
    """Still moving after the commands stopped? None when too few samples show it."""
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
        extra["duration_s"] = after[-1].time - burst.end
        text = f"stopped when the commands stopped (still for {after[-1].time - burst.end:.1f} s)"
        return Finding(burst.name, burst.end, CHECK_STOP, OBEYED, text, extra)
    still = moved_at - burst.end
    extra["duration_s"] = still
    text = f"still moving {still:.1f} s after the commands stopped (moved {moved:.1f} deg more)"
    if moved_at >= after[-1].time:
        text = (
            f"still moving {still:.1f} s after the commands stopped, and still moving "
            f"(moved {moved:.1f} deg more)"
        )
    return Finding(burst.name, burst.end, CHECK_STOP, NOT_OBEYED, text, extra)


def judge_repeat(burst: Burst, rate_verdict: str) -> Finding | None:
    """Commands repeated too slowly to keep the gimbal moving (None when fast enough)."""
    verdict = OBEYED if rate_verdict == OBEYED else PARTIAL
    if burst.count == 1:
        once: dict[str, Any] = {"command_count": 1}
        return Finding(burst.name, burst.start, CHECK_REPEAT, verdict, _SENT_ONCE, once)
    mean = burst.interval_sum / (burst.count - 1)
    if mean <= SLOW_REPEAT_S:
        return None
    text = (
        f"repeated every {mean:.2f} s on average (longest pause {burst.interval_max:.2f} s); the "
        f"document recommends {RECOMMENDED_REPEAT_S * 1000:.0f} ms to keep it moving"
    )
    extra: dict[str, Any] = {
        "interval_s": mean,
        "max_interval_s": burst.interval_max,
        "command_count": burst.count,
    }
    return Finding(burst.name, burst.start, CHECK_REPEAT, verdict, text, extra)
