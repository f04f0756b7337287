"""Bring the gimbal to an attitude and wait until its feedback shows it there, or say why not.

``bring_to`` is the one way the bench tools put a gimbal where they need it: every
step of ``check`` starts from its own attitude, whatever attitude the gimbal was left
in, and a replay starts from a flight's first attitude. It needs only a way to send a
command's 8 data bytes (``Sender``: the check's link), the attitude feedback as it comes
(``Feedback``: the check's ``Observer``) and a clock (the wall clock, or a simulated
one). The goals are ``(axis, angle)`` pairs: ``pitch``, ``motor_yaw`` (from the
airframe's nose) or ``yaw`` (from north), each reached with one ``specified_angle``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

from analyzer import wall_clock
from analyzer.analysis.samples import MOTOR_YAW, PITCH, YAW, Sample
from analyzer.analysis.targets import SETTLED_S, STILL_DEG
from analyzer.analysis.yaw_geometry import angle_error, motor_limit, reachable, travel
from analyzer.protocol.codec import EncodeError, encode_command

Goals = tuple[tuple[str, float], ...]  # (axis, angle): pitch, motor_yaw or yaw

FRESH_S = 1.0  # feedback older than this (two periods) does not say where the gimbal is now
# How every bench tool leaves the gimbal (at the end, on an error, on Ctrl-C): speeds 0
# first (a gimbal_control stream stops), then back to the centre.
CENTRING: tuple[tuple[str, dict[str, Any]], ...] = (
    ("gimbal_control", {"pan_speed_dps": 0.0, "tilt_speed_dps": 0.0}),
    ("forward", {}),
)
CENTRE: Goals = ((PITCH, 0.0), (MOTOR_YAW, 0.0))
MIN_SETTLE_WAIT_S = 1.5  # a move is not taken as over (the gimbal still) before this
ATTEMPTS = 4  # the commands are sent this often at most, while the gimbal comes nearer
LABELS = {PITCH: "pitch", MOTOR_YAW: "yaw motor", YAW: "yaw from north"}


class Sender(Protocol):
    """Sends one command's 8 data bytes; returns when it went (Unix seconds)."""

    def send(self, data: bytes) -> float: ...


class Feedback(Protocol):
    """The attitude feedback as it comes (``analyzer.check.observer.Observer``)."""

    @property
    def samples(self) -> list[Sample]: ...

    def wait(self, done: Callable[[], bool], until: float) -> bool: ...


class Clock(Protocol):
    """Unix time (the times commands and feedback carry), a monotonic clock for waits,
    and sleeping."""

    def time(self) -> float: ...

    def monotonic(self) -> float: ...

    def sleep(self, seconds: float) -> None: ...


class RealClock:
    """The real clocks: live timestamps from the process's wall clock (``wall_clock.now``)."""

    def time(self) -> float:
        return wall_clock.now()

    def monotonic(self) -> float:
        return time.monotonic()

    def sleep(self, seconds: float) -> None:
        time.sleep(max(0.0, seconds))


WALL_CLOCK = RealClock()


@dataclass(frozen=True)
class Arrival:
    """How ``bring_to`` went: ``reached``, else ``reason`` says why not; the commands it
    sent (none when the gimbal was already there), how long it took, the last attitude
    the feedback gave, and whether any feedback came after the commands (``heard``)."""

    reached: bool
    reason: str
    sent: tuple[str, ...]
    took_s: float
    sample: Sample | None
    heard: bool = True


def describe(goals: Goals) -> str:
    """'pitch 0.0, yaw motor 120.0'."""
    return ", ".join(f"{LABELS[axis]} {angle:.1f}" for axis, angle in goals)


def commands_for(goals: Goals) -> list[tuple[str, dict[str, Any]]]:
    """The ``specified_angle`` commands (name, parameters) that ask for ``goals``."""
    out: list[tuple[str, dict[str, Any]]] = []
    for axis, angle in goals:
        if axis == PITCH:
            out.append(("specified_angle", {"axis": "pitch", "pitch_deg": angle}))
        elif axis in (MOTOR_YAW, YAW):
            frame = "airframe" if axis == MOTOR_YAW else "geodetic"
            params = {"axis": "yaw", "yaw_deg": round(angle % 360.0, 1)}
            out.append(("specified_angle", {**params, "coordinate_system": frame}))
        else:
            raise ValueError(f"no command turns the gimbal's {axis!r}")
    return out


def at_attitude(samples: list[Sample], goals: Goals, tolerance: float) -> bool:
    """The last two of ``samples`` are within ``tolerance`` of every goal (two, so that
    one taken while passing through does not count)."""
    recent = samples[-2:]
    return len(recent) == 2 and all(
        abs(angle_error(axis, angle, s)) <= tolerance for s in recent for axis, angle in goals
    )


def stopped(samples: list[Sample], axes: list[str], elapsed: float) -> bool:
    """``samples`` (those since a command sent ``elapsed`` seconds ago) show no axis of
    ``axes`` moving for SETTLED_S: the analysis' own rule for an answer that is final."""
    if elapsed < MIN_SETTLE_WAIT_S or len(samples) < 3:
        return False
    last = samples[-1]
    for s in reversed(samples):
        if any(abs(s.value(a) - last.value(a)) >= STILL_DEG for a in axes):
            return False
        if last.time - s.time >= SETTLED_S + 0.1:
            return True
    return False


def time_needed(goals: Goals, sample: Sample | None, slew_dps: float) -> float:
    """Seconds the longest turn to ``goals`` takes at ``slew_dps`` (the motor's way round
    for yaw; a half turn when where the gimbal points is not known)."""
    turns = [180.0] if sample is None else [abs(travel(a, t, sample)) for a, t in goals]
    return max(turns, default=0.0) / slew_dps


def bring_to(
    sender: Sender,
    feedback: Feedback,
    goals: Goals,
    *,
    tolerance_deg: float,
    timeout_s: float,
    clock: Clock = WALL_CLOCK,
    attempts: int = ATTEMPTS,
    max_turn_deg: float | None = None,
) -> Arrival:
    """Turn the gimbal to ``goals`` and wait until two feedback messages in a row show it
    within ``tolerance_deg`` of every goal: at most ``timeout_s`` after the commands, and
    no longer once it has stopped elsewhere (``stopped``).

    Sends nothing when the latest feedback (less than FRESH_S old) already shows it
    there. Otherwise sends one ``specified_angle`` per goal, and again (``attempts`` in
    all) while a gimbal that stopped short came nearer each time. A turn longer than
    ``max_turn_deg`` is made in legs of equal length (the way the axis turns), each
    waited for alike: so that each command asks for no more than the gimbal does within
    the time a judgement of it allows. The Arrival's ``reason`` says what stood in the
    way: an angle no command can ask for or the motor cannot reach, no feedback, or
    where the gimbal stopped instead.
    """
    samples = feedback.samples
    ways = legs(goals, samples[-1] if samples else None, max_turn_deg)
    arrival = Arrival(False, "", (), 0.0, None)
    for way in ways:
        leg = _arrive(sender, feedback, way, tolerance_deg, timeout_s, clock, attempts)
        arrival = Arrival(
            leg.reached,
            leg.reason,
            arrival.sent + leg.sent,
            arrival.took_s + leg.took_s,
            leg.sample,
            leg.heard,
        )
        if not leg.reached:
            break
    return arrival


def legs(goals: Goals, sample: Sample | None, max_turn_deg: float | None) -> list[Goals]:
    """``goals`` and the goals on the way to them: a turn (along the way the axis turns)
    longer than ``max_turn_deg`` in as many equal legs as it takes."""
    if sample is None or not max_turn_deg:
        return [goals]
    turns = {axis: travel(axis, angle, sample) for axis, angle in goals}
    count = max(math.ceil(abs(turn) / max_turn_deg - 1e-9) for turn in turns.values())
    out: list[Goals] = []
    for n in range(1, count):
        share = n / count
        way: list[tuple[str, float]] = []
        for axis, turn in turns.items():
            if axis == PITCH:
                way.append((PITCH, round(sample.pitch + turn * share, 1)))
            else:  # yaw either way: the motor turns
                way.append((MOTOR_YAW, round(sample.motor_yaw + turn * share, 1)))
        out.append(tuple(way))
    return [*out, goals]


def _arrive(
    sender: Sender,
    feedback: Feedback,
    goals: Goals,
    tolerance_deg: float,
    timeout_s: float,
    clock: Clock,
    attempts: int,
) -> Arrival:
    """One leg of ``bring_to``."""
    began = clock.monotonic()
    samples = feedback.samples
    last = samples[-1] if samples else None
    if last is not None and clock.time() - last.time <= FRESH_S:
        if at_attitude(samples, goals, tolerance_deg):
            return Arrival(True, "", (), 0.0, last)
        for axis, angle in goals:
            if axis != PITCH and not reachable(axis, angle, last):
                why = f"{describe(((axis, angle),))} is beyond the yaw motor's range"
                return Arrival(False, f"{why} +-{motor_limit(last):g}", (), 0.0, last)
    frames: list[tuple[str, bytes]] = []
    for name, params in commands_for(goals):
        try:
            frames.append((command_words(name, params), encode_command(name, **params)))
        except EncodeError as exc:
            return Arrival(False, f"{describe(goals)} cannot be asked for: {exc}", (), 0.0, last)
    axes = [axis for axis, _ in goals]
    said: tuple[str, ...] = ()
    seen: list[Sample] = []
    for _ in range(attempts):
        sent = 0.0
        for _, data in frames:
            sent = sender.send(data)
        said += tuple(text for text, _ in frames)
        begun = seen[-1] if seen else last

        def after(since: float = sent) -> list[Sample]:
            return [s for s in feedback.samples if s.time > since]

        def over(since: float = sent) -> bool:
            seen = after(since)
            return at_attitude(seen, goals, tolerance_deg) or stopped(
                seen, axes, clock.time() - since
            )

        feedback.wait(over, clock.monotonic() + timeout_s)
        seen = after()
        if at_attitude(seen, goals, tolerance_deg):
            return Arrival(True, "", said, clock.monotonic() - began, seen[-1])
        if not seen or not _closer(goals, begun, seen[-1], tolerance_deg):
            break  # no feedback, or it did not come nearer: asking again will not help
    took = clock.monotonic() - began
    why = _why_not(goals, last, seen, took)
    return Arrival(False, why, said, took, seen[-1] if seen else last, bool(seen))


def _closer(goals: Goals, before: Sample | None, now: Sample, tolerance: float) -> bool:
    """``now`` is nearer every goal it is off than ``before`` by more than the tolerance
    (a gimbal that stopped short on the way: asked again, it goes on)."""
    if before is None:
        return False
    return all(
        abs(angle_error(axis, angle, now)) <= tolerance
        or abs(angle_error(axis, angle, before)) - abs(angle_error(axis, angle, now)) > tolerance
        for axis, angle in goals
    )


def centre(
    sender: Sender,
    feedback: Feedback,
    *,
    tolerance_deg: float,
    timeout_s: float | None,
    clock: Clock = WALL_CLOCK,
) -> bool | None:
    """Send CENTRING; with ``timeout_s``, wait that long for two feedback messages in a
    row showing the gimbal centred and say whether they came (None: not waited for)."""
    sent = 0.0
    for name, params in CENTRING:
        sent = sender.send(encode_command(name, **params))
    if timeout_s is None:
        return None

    def there() -> bool:
        after = [s for s in feedback.samples if s.time > sent]
        return at_attitude(after, CENTRE, tolerance_deg)

    return feedback.wait(there, clock.monotonic() + timeout_s)


def command_words(name: str, params: dict[str, Any]) -> str:
    """A command in words: 'specified_angle axis=pitch pitch_deg=-30'."""
    shown = " ".join(
        f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in params.items()
    )
    return f"{name} {shown}"


def _why_not(goals: Goals, before: Sample | None, seen: list[Sample], waited_s: float) -> str:
    """Where the gimbal is instead of at ``goals``, axis by axis."""
    if not seen:
        return f"no attitude feedback came within {waited_s:.1f} s of the commands"
    last = seen[-1]
    start = before if before is not None else seen[0]
    parts = []
    for axis, angle in goals:
        off = angle_error(axis, angle, last)
        moved = abs(travel(axis, angle, start) - travel(axis, angle, last))
        how = "it did not move" if moved < 0.5 else f"moved {moved:.1f} deg"
        parts.append(f"{LABELS[axis]} at {last.value(axis):.1f}, {abs(off):.1f} deg off ({how})")
    return f"not at {describe(goals)} after {waited_s:.1f} s: " + "; ".join(parts)
