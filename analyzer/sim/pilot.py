"""A pilot's stick as a ground station streams it: smooth movements, a reading's noise, 20 Hz."""

from __future__ import annotations

import math
import random
from dataclasses import dataclass

STICK_HZ = 20.0  # the document recommends a gimbal_control every 50 ms
NOISE_DPS = 0.03  # an analog stick's reading jitters by a few 0.01 deg/s
WOBBLE = 0.06  # the hand's slow wobble, as a fraction of the peak speed
WOBBLE_HZ = 0.7
RAMP = 0.25  # the stick rises to its peak (and falls back) over this fraction of a movement
SPEED_LIMIT = 100.0  # deg/s, chapter 2.1: speeds are within [-100, 100]
DEAD_BAND_DPS = 0.1  # a stick this near its centre reads exactly 0


@dataclass(frozen=True)
class Stick:
    """One movement of a pilot's stick: the speeds rise smoothly to ``pan_dps`` /
    ``tilt_dps`` and fall back over the movement's length, the hand wobbles a little and
    the reading jitters; then the stick is centred for ``centred_s`` seconds, during which
    the ground station keeps sending 0, 0 (as many do while the stick is centred).
    ``released``: the pilot lets go of the stick at the end of the movement instead of
    bringing it back, so the last commands are still at speed, then the station stops.

    ``seed`` makes the noise repeatable; two movements with the same seed jitter alike."""

    pan_dps: float = 0.0
    tilt_dps: float = 0.0
    centred_s: float = 0.0
    noise_dps: float = NOISE_DPS
    wobble: float = WOBBLE
    seed: int = 0
    released: bool = False

    def speeds(self, elapsed: float, duration: float) -> tuple[float, float]:
        """(pan, tilt) in deg/s ``elapsed`` seconds into a movement of ``duration`` seconds;
        0, 0 after it (the stick centred: a dead band gives exactly 0)."""
        if not -1e-6 <= elapsed <= duration + 1e-6 or duration <= 0:
            return 0.0, 0.0
        x = min(1.0, max(0.0, elapsed / duration))
        shape = 1.0 if self.released and x > 0.5 else profile(x)
        hand = 1.0 + self.wobble * math.sin(2 * math.pi * WOBBLE_HZ * elapsed + self.seed)
        rng = random.Random(hash((self.seed, round(elapsed * 1000))))
        pan, tilt = (
            _reading(held + rng.gauss(0.0, self.noise_dps))
            if abs(held := peak * shape * hand) >= DEAD_BAND_DPS
            else 0.0
            for peak in (self.pan_dps, self.tilt_dps)
        )
        return pan, tilt


def profile(x: float) -> float:
    """0 -> 1 -> 0 over x in [0, 1]: a smooth rise over RAMP, a plateau, a smooth fall."""
    if x < RAMP:
        return math.sin(math.pi / 2 * x / RAMP) ** 2
    if x > 1 - RAMP:
        return math.sin(math.pi / 2 * (1 - x) / RAMP) ** 2
    return 1.0


def _reading(value: float) -> float:
    """A speed as the command carries it: 0.01 deg/s steps within the document's range."""
    return round(min(SPEED_LIMIT, max(-SPEED_LIMIT, value)), 2)
