"""Random ground-station scripts for the soundness harness: what a ground station may send.

A script is a series of episodes, each the commands of one intent: a target (pitch,
yaw from the nose or from north, look_down, forward), sent once or re-sent until it is
reached; a stick movement played on a pilot's stick (``analyzer.sim.pilot``), with or
without zeros after it, or let go at speed; a tracking session (the first box off
centre, then box updates at 10 Hz near the centre, mostly a tracking_stop); a zoom in
and its stop. An episode may start before the gimbal has finished the one before (it
is interrupted) or after a pause. The scripts ask only for what a healthy gimbal can
do: targets inside its range that it reaches within the time allowed (at the
simulator's 60 deg/s), stick movements that stay off its stops. The generator keeps,
per axis, the interval the gimbal may be in to ensure that.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass, field
from typing import Any

from analyzer.sim.ground import REPEAT_S, Step
from analyzer.sim.pilot import Stick

PITCH_RANGE = (-100.0, 55.0)  # inside the stops (-110..60) and what specified_angle takes
YAW_RANGE = (-160.0, 160.0)  # the yaw motor, inside its +-170 stops
SLEW_DPS = 60.0  # the simulated gimbal's slew
MAX_TURN_S = 3.8  # a target's turn takes at most this (the time allowed is 5 s)
HOLD_S = 0.3  # a command's speeds hold this long (the simulator's model)
CENTRE = 4096  # the image's centre in tracking coordinates
FOV = (60.0, 34.0)  # the simulator's field of view at 1x (horizontal, vertical)
FIRST_AT_S = 1.2  # a fault's first episode starts once the feedback has begun
FIRST_TURN_DEG = 20.0  # and a target in it asks for a turn this long at least
QUIET_AFTER_FIRST_S = 4.0  # nothing is sent this long after the first episode's end
TARGETS = ("pitch", "yaw_airframe", "yaw_geodetic", "look_down", "forward")


@dataclass
class Where:
    """The angles the gimbal may be at (pitch, yaw motor), as intervals."""

    pitch: tuple[float, float] = (0.0, 0.0)
    yaw: tuple[float, float] = (0.0, 0.0)

    def turn_to(self, pitch: float | None, yaw: float | None) -> float:
        """The longest turn (deg) to these angles from anywhere it may be."""
        turns = [0.0]
        if pitch is not None:
            turns += [abs(pitch - p) for p in self.pitch]
        if yaw is not None:
            turns += [abs(yaw - y) for y in self.yaw]
        return max(turns)


def _hull(a: tuple[float, float], b: tuple[float, float]) -> tuple[float, float]:
    return min(a[0], b[0]), max(a[1], b[1])


@dataclass
class Script:
    """A script being written: its steps, where the gimbal may be, when it is free."""

    rng: random.Random
    heading: float
    where: Where = field(default_factory=Where)
    steps: list[Step] = field(default_factory=list)
    at: float = 0.3  # when the next episode may start
    kinds: list[tuple[str, float, float]] = field(default_factory=list)  # (kind, from, to)

    # -- episodes ----------------------------------------------------------------------

    def target(self, kind: str | None = None, *, first: bool = False) -> None:
        """A target; ``first``: it shows a fault, so it is one the gimbal must turn to
        (look_down and forward from elsewhere: a pitch target first), and a geodetic
        yaw is one that a gimbal taking it from the nose could reach too."""
        rng = self.rng
        kind = kind or rng.choice(TARGETS)
        fixed = {"look_down": (-90.0, None), "forward": (0.0, 0.0)}.get(kind)
        if first and fixed is not None and self.where.turn_to(*fixed) < FIRST_TURN_DEG:
            self.target("pitch", first=True)
            self.at = max(self.at, self.kinds[-1][2])  # once it is there
        pitch = yaw = None
        params: dict[str, Any] = {}
        name = "specified_angle"
        for _ in range(500):  # a target the gimbal reaches in time from anywhere it may be
            if kind == "pitch":
                pitch = round(rng.uniform(*PITCH_RANGE), 1)
                params = {"axis": "pitch", "pitch_deg": pitch}
            elif kind in ("yaw_airframe", "yaw_geodetic"):
                yaw = round(rng.uniform(*YAW_RANGE), 1)
                if kind == "yaw_airframe":
                    params = {"axis": "yaw", "yaw_deg": round(yaw % 360, 1)}
                    params["coordinate_system"] = "airframe"
                else:
                    north = round((self.heading + yaw) % 360, 1)
                    params = {"axis": "yaw", "yaw_deg": north, "coordinate_system": "geodetic"}
                    mixed = (north + 180.0) % 360.0 - 180.0  # the nose's angle of that number
                    if first and (
                        abs(mixed) > YAW_RANGE[1]
                        or self.where.turn_to(None, mixed) / SLEW_DPS > MAX_TURN_S
                    ):
                        continue
            elif kind == "look_down":
                name, pitch = "look_down", -90.0
            else:
                name, pitch, yaw = "forward", 0.0, 0.0
            turn = self.where.turn_to(pitch, yaw)
            if turn / SLEW_DPS <= MAX_TURN_S and (fixed or not first or turn >= FIRST_TURN_DEG):
                break
        else:
            kind, name, params, pitch, yaw = "forward", "forward", {}, 0.0, 0.0
        start = self.at
        sends = [start]
        if rng.random() < 0.35:  # re-sent until it is (surely) reached
            every = rng.uniform(0.1, 0.5)
            sends += [start + every * n for n in range(1, int(rng.uniform(0.5, 4.0) / every) + 1)]
        self.steps += [Step(t, name, dict(params)) for t in sends]
        turn = self.where.turn_to(pitch, yaw) / SLEW_DPS
        after = Where(
            self.where.pitch if pitch is None else (pitch, pitch),
            self.where.yaw if yaw is None else (yaw, yaw),
        )
        self._next(kind, sends[-1], start + turn + 0.8, after)

    def stick(
        self, length: float | None = None, *, released: bool | None = None, first: bool = False
    ) -> None:
        rng = self.rng
        length = length if length is not None else rng.uniform(0.4, 4.0)
        centred = rng.choice((0.0, rng.uniform(0.1, 1.5)))
        released = rng.random() < 0.15 if released is None else released
        seed = rng.randrange(1_000_000)
        axes = rng.choice(((0,), (1,), (0, 1)))
        speeds = [0.0, 0.0]
        for axis in axes:
            speeds[axis] = rng.uniform(5.0, 60.0) * rng.choice((-1.0, 1.0))
        if first:  # it shows the fault: a stick moved well off centre
            speeds = [math.copysign(max(20.0, abs(v)), v) if v else 0.0 for v in speeds]
        turns = _stick_turns(Stick(speeds[0], speeds[1], seed=seed, released=released), length)
        bounds = (YAW_RANGE, PITCH_RANGE)
        intervals = [self.where.yaw, self.where.pitch]
        for axis in (0, 1):
            if not turns[axis]:
                continue
            lo, hi = intervals[axis]
            low, high = bounds[axis]
            room = (high - hi) if turns[axis] > 0 else (lo - low)
            other = (lo - low) if turns[axis] > 0 else (high - hi)
            if other > room:  # the other way has more room: turn that way
                speeds[axis], turns[axis], room = -speeds[axis], -turns[axis], other
            # let go at speed: room for 2 s more at that speed (a gimbal that drifts on)
            needed = abs(turns[axis]) + (2.2 * abs(speeds[axis]) if released else 0.0)
            if needed > room - 3.0:  # slower, to stay off the stop
                scale = max(0.0, room - 3.0) / needed
                speeds[axis] *= scale
                turns[axis] *= scale
            intervals[axis] = (lo + turns[axis], hi + turns[axis])
        stick = Stick(speeds[0], speeds[1], centred_s=centred, seed=seed, released=released)
        start = self.at
        self.steps.append(Step(start, "gimbal_control", {}, until=start + length, stick=stick))
        end = start + length + centred
        self._next("stick", end, start + length + HOLD_S + 1.0, Where(intervals[1], intervals[0]))

    def tracking(self, *, first: bool = False) -> None:
        """A tracking session; ``first``: it shows a fault, so it lasts past the flag's
        allowance and ends with a tracking_stop."""
        rng = self.rng
        start = self.at
        dx, dy = rng.uniform(-1500, 1500), rng.uniform(-1000, 1000)
        turn_yaw, turn_pitch = dx / CENTRE * FOV[0] / 2, -dy / CENTRE * FOV[1] / 2
        yaw = (self.where.yaw[0] + turn_yaw, self.where.yaw[1] + turn_yaw)
        pitch = (self.where.pitch[0] + turn_pitch, self.where.pitch[1] + turn_pitch)
        if yaw[0] < YAW_RANGE[0] or yaw[1] > YAW_RANGE[1]:
            dx, yaw = 0.0, self.where.yaw
        if pitch[0] < PITCH_RANGE[0] or pitch[1] > PITCH_RANGE[1]:
            dy, pitch = 0.0, self.where.pitch
        box = {"x": round(CENTRE + dx), "y": round(CENTRE + dy), "width": 480, "height": 320}
        self.steps.append(Step(start, "tracking", box))
        updates = int(rng.uniform(2.5 if first else 0.5, 6.0) * 10)
        for n in range(1, updates + 1):
            near = {"x": CENTRE + rng.randint(-8, 8), "y": CENTRE + rng.randint(-6, 6)}
            self.steps.append(Step(start + 0.1 * n, "tracking", {**box, **near}))
        last = start + 0.1 * updates
        if first or rng.random() < 0.8:
            last += rng.uniform(0.1, 0.6)
            self.steps.append(Step(last, "tracking_stop"))
        self._next("tracking", last, last + 1.5, Where(pitch, yaw))  # the flag's allowance

    def zoom(self) -> None:
        start = self.at
        self.steps.append(Step(start, "zoom", {"action": "zoom_in"}))
        stop = start + self.rng.uniform(0.2, 1.5)
        self.steps.append(Step(stop, "zoom", {"action": "stop"}))
        self._next("zoom", stop, stop, self.where)

    def _next(self, kind: str, last: float, done: float, after: Where) -> None:
        """After an episode whose commands end at ``last``, which the gimbal has done by
        ``done`` and leaves it ``after``: when the next one starts, and where the gimbal
        may be then (anywhere on the way, when the next one interrupts it)."""
        rng = self.rng
        self.kinds.append((kind, last, done))
        roll = rng.random()
        if roll < 0.25:  # the next one interrupts this one
            gap = rng.uniform(0.05, max(0.1, done - last))
        elif roll < 0.75:
            gap = rng.uniform(0.2, 2.0) + max(0.0, done - last)
        else:
            gap = rng.uniform(2.0, 5.0) + max(0.0, done - last)
        self.at = last + max(REPEAT_S, gap)
        if self.at >= done:
            self.where = after
        else:
            self.where = Where(
                _hull(self.where.pitch, after.pitch), _hull(self.where.yaw, after.yaw)
            )


def _stick_turns(stick: Stick, length: float) -> list[float]:
    """(pan, tilt) degrees a movement of ``length`` seconds asks for, as the simulator
    integrates it (each command's speeds until the next; a stick let go holds its last
    speeds for HOLD_S)."""
    turns = [0.0, 0.0]
    count = int(length / REPEAT_S + 1e-6) + 1
    last = (0.0, 0.0)
    for n in range(count):
        last = stick.speeds(n * REPEAT_S, length)
        for axis in (0, 1):
            turns[axis] += last[axis] * REPEAT_S
    for axis in (0, 1):
        turns[axis] += last[axis] * (HOLD_S - REPEAT_S)
    return turns


def random_script(
    rng: random.Random,
    duration: float,
    heading: float,
    attitude: tuple[float, float],
    first: str | None = None,
) -> tuple[tuple[Step, ...], float]:
    """Episodes until ``duration``, from a gimbal at ``attitude`` (pitch, yaw motor) under
    an aircraft heading ``heading``. ``first``: the kind of the first episode, which
    shows a fault (a target kind, ``long_stick``, ``released_stick`` let go at speed,
    ``tracking``), once the feedback has begun and followed by a pause of
    QUIET_AFTER_FIRST_S. Returns the steps and when the gimbal has done the first
    episode (0 without one)."""
    script = Script(rng, heading, Where((attitude[0],) * 2, (attitude[1],) * 2))
    first_done = 0.0
    if first is not None:  # once the feedback has begun
        script.at = FIRST_AT_S
    if first == "long_stick":
        script.stick(rng.uniform(2.0, 4.0), first=True)
    elif first == "released_stick":
        script.stick(rng.uniform(2.0, 4.0), released=True, first=True)
    elif first == "tracking":
        script.tracking(first=True)
    elif first is not None:
        script.target(first, first=True)
    if first is not None:  # then a pause: what the gimbal does after it shows
        first_done = max(done for _, _, done in script.kinds)
        script.at = max(script.at, first_done + QUIET_AFTER_FIRST_S)
    while script.at < duration:
        roll = rng.random()
        if roll < 0.4:
            script.target()
        elif roll < 0.75:
            script.stick()
        elif roll < 0.9:
            script.tracking()
        else:
            script.zoom()
    steps = sorted((s for s in script.steps if s.at < duration), key=lambda s: s.at)
    return tuple(steps), first_done
