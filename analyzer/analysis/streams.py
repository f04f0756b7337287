"""gimbal_control streams: a ground station's commands of one component, cut into stick movements.

Commands of one component (gimbal, dual-sensor) that follow each other within
``STREAM_GAP_S`` are one stream, whatever their speeds: a pilot's hand changes them in
every command. A movement is a stretch of the stream with the stick off centre; it ends
with a command of 0, 0 (many ground stations keep sending zeros while the stick is
centred), with a pause that ends the stream, or when another motion command takes over.
Each movement is judged once (``analyzer.analysis.rates``), the stream's cadence once.

A late gimbal's motion belongs to the movement that caused it, across every boundary:
a movement carries the stream's commands from just before it (``prior``: the previous
movement's end may still be turning the gimbal), takes the commands that follow it
until it is judged, and when another motion command takes over, its feedback window
reaches on by the longest lag (``free_until`` says when the other command came).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from enum import Enum
from itertools import islice

from analyzer.analysis.motion_fit import LAG_MAX_S, CommandedMotion, StickCommand

STREAM_GAP_S = 1.0  # commands further apart than this are separate streams
RECOMMENDED_REPEAT_S = 0.05  # chapter 2.1, 0x04: "50ms at a time is recommended"
# A command's speeds are taken to hold until the next command, or this long when none
# comes sooner: the gimbal "will stop rotating" when the commands stop, and the document
# does not say how soon; 0.3 s, as gimbals of this kind coast.
HOLD_S = 0.3
SLOW_REPEAT_S = 2 * RECOMMENDED_REPEAT_S  # a mean interval above this is too slow
PAUSE_STOP_S = HOLD_S  # a silence longer than the hold inside a movement: it stopped there
MAX_MOVEMENT_S = 60.0  # a stick held off centre longer is judged in pieces this long
TAIL_S = HOLD_S + LAG_MAX_S  # the feedback is watched this long after a movement ends
PRIOR_S = HOLD_S + LAG_MAX_S  # commands this long before a movement may still turn the gimbal


class EndedBy(Enum):
    """How a movement's end was seen (its value: the words)."""

    ZEROS = "zeros"  # a command of 0, 0: the stick came back
    PAUSE = "pause"  # the stream paused
    OTHER_COMMAND = "another motion command"  # it took over (``Movement.cut_short`` names it)
    INPUT_ENDED = "the input ended"
    LENGTH = "length"  # held off centre longer than MAX_MOVEMENT_S: judged in pieces

    def __str__(self) -> str:
        return self.value

    @property
    def centred(self) -> bool:
        """The stick was seen back at the centre: the gimbal must then hold still."""
        return self in (EndedBy.ZEROS, EndedBy.PAUSE)


@dataclass(eq=False)
class Movement:
    """One stick movement: the commands from its first off-centre one, and those that
    follow until its judgement (zeros, the next movement's start), for the motion the
    stream asked for."""

    component: str
    start: float
    stream: StickStream
    commands: list[StickCommand] = field(default_factory=list)
    count: int = 0  # off-centre commands
    last: float = 0.0  # the last off-centre command
    interval_sum: float = 0.0
    interval_max: float = 0.0
    peak_pan: float = 0.0
    peak_tilt: float = 0.0
    end: float | None = None  # when the stick came back (None while it is off centre)
    ended_by: EndedBy | None = None  # None while the stick is off centre
    window_end: float | None = None  # the feedback is judged up to here
    cut_short: str = ""  # what ended the window early, if anything
    prior: list[StickCommand] = field(default_factory=list)  # the stream's just before it
    other_before: float | None = None  # the last other motion command before it
    other_name: str = ""  # and its name
    own_before: float | None = None  # the stream's newest speed older than ``prior``
    free_from: float | None = None  # only the stream turns the gimbal from here (None: before)
    free_until: float | None = None  # another motion command took over here
    followed: tuple[float, dict[int, float]] | None = None  # its fit: lag, ratio per axis

    _motion: tuple[int, CommandedMotion] | None = field(default=None, repr=False)

    def motion(self) -> CommandedMotion:
        """The motion its commands ask for, those just before it (``prior``) first."""
        count = len(self.prior) + len(self.commands)
        if self._motion is None or self._motion[0] != count:
            self._motion = count, CommandedMotion([*self.prior, *self.commands], HOLD_S)
        return self._motion[1]

    def add(self, command: StickCommand) -> None:
        """A command of the stream while the movement is open or awaits its judgement."""
        self.commands.append(command)
        if self.end is not None or (command.pan == 0 and command.tilt == 0):
            return
        if self.count:
            interval = command.time - self.last
            self.interval_sum += interval
            self.interval_max = max(self.interval_max, interval)
        self.count += 1
        self.last = command.time
        if abs(command.pan) > abs(self.peak_pan):
            self.peak_pan = command.pan
        if abs(command.tilt) > abs(self.peak_tilt):
            self.peak_tilt = command.tilt

    def close(self, end: float, why: EndedBy) -> None:
        """The stick is centred from ``end`` on (``why`` says how that was seen)."""
        if self.end is None:
            self.end, self.ended_by = end, why
            self.window_end = end + TAIL_S

    def cut(self, t: float, name: str) -> None:
        """Another motion command ``name`` at ``t``: the gimbal answers it, not this
        movement, from ``t`` plus its lag; the window reaches on by the longest lag."""
        why = f"{name} came"
        if self.end is None:
            self.close(min(t, self.last + HOLD_S), EndedBy.OTHER_COMMAND)
        assert self.window_end is not None
        if t + LAG_MAX_S < self.window_end:
            self.window_end, self.cut_short = t + LAG_MAX_S, why
        if self.free_until is None or t < self.free_until:
            self.free_until = t

    @property
    def interval_mean(self) -> float | None:
        return self.interval_sum / (self.count - 1) if self.count > 1 else None

    @property
    def stopped_at(self) -> float:
        """When the commands stopped asking for speed: the 0, 0 command, else the last."""
        if self.ended_by is EndedBy.ZEROS and self.end is not None:
            return self.end
        return self.last

    def too_slow(self) -> bool:
        """Repeated too slowly to keep the gimbal moving: sent once and then nothing for
        longer than a command holds (a stick nudged and centred at once, or a command
        another one followed, is no cadence problem), a mean interval over twice the
        document's, or a pause the gimbal stops in."""
        mean = self.interval_mean
        if mean is None:
            if self.ended_by is EndedBy.PAUSE:
                return True
            return (
                self.ended_by is EndedBy.ZEROS
                and self.end is not None
                and self.end - self.last > HOLD_S
            )
        return mean > SLOW_REPEAT_S or self.interval_max > PAUSE_STOP_S


@dataclass(eq=False)
class StickStream:
    """The open stream of one component: its last command and its movement under way."""

    component: str
    last: float
    movement: Movement | None = None
    cadence_said: bool = False  # a stream's cadence is judged once (the judge records it)


class Streams:
    """The open streams by component and the movements awaiting their judgement
    (``waiting``, which ``analyzer.analysis.stick_judge`` judges once their feedback
    window is over).

    ``command`` takes a gimbal_control; ``end_quiet`` ends the streams that paused;
    ``cut`` and ``end`` close what another command or the input's end interrupts."""

    def __init__(self) -> None:
        self.open: dict[str, StickStream] = {}
        self.waiting: list[Movement] = []  # closed, their window still open
        self.other_at: float | None = None  # the last other motion command
        self.other_name = ""
        self.recent: dict[
            str, deque[StickCommand]
        ] = {}  # a component's commands of the last PRIOR_S
        self.forgotten: dict[str, float] = {}  # the newest one off centre no longer kept
        # A stream opened or ended, a movement started, closed or was cut, a stop check
        # came or was cut (its judge sets that): when judgements are due is to be seen again.
        self.reshaped = False

    def command(self, t: float, component: str, pan: float, tilt: float) -> list[Movement]:
        """One gimbal_control; returns the movements it closed (their stop checks start)."""
        closed = self.end_quiet(t) if self.open else []
        stream = self.open.get(component)
        command = StickCommand(t, pan, tilt)
        if self.waiting:
            for waiting in self.waiting:  # its motion goes on until it is judged
                if waiting.component == component:
                    waiting.add(command)
        if stream is None:
            stream = self.open[component] = StickStream(component, t)
            self.reshaped = True
        else:
            stream.last = t
        recent = self._remember(component, command)
        movement = stream.movement
        centred = pan == 0 and tilt == 0
        if movement is not None:
            if t - movement.start >= MAX_MOVEMENT_S and not centred:
                movement.commands.append(command)  # the stick goes on: so does the motion
                movement.close(t, EndedBy.LENGTH)
                self._retire(stream)
                closed.append(movement)
                movement = None
            else:
                movement.add(command)
                if centred:
                    movement.close(t, EndedBy.ZEROS)
                    self._retire(stream)
                    closed.append(movement)
                return closed
        if not centred:
            movement = stream.movement = Movement(component, t, stream)
            self.reshaped = True
            movement.prior = list(islice(recent, len(recent) - 1))  # those before it
            movement.other_before, movement.other_name = self.other_at, self.other_name
            movement.own_before = self.forgotten.get(component)
            movement.add(command)
        return closed

    def _remember(self, component: str, command: StickCommand) -> deque[StickCommand]:
        """Keep ``command`` among the component's recent ones (returned, it the last)."""
        recent = self.recent.get(component)
        if recent is None:
            recent = self.recent[component] = deque()
        oldest = command.time - PRIOR_S
        while recent and recent[0].time < oldest:
            old = recent.popleft()
            if old.pan or old.tilt:
                self.forgotten[component] = old.time
        recent.append(command)
        return recent

    def end_quiet(self, t: float) -> list[Movement]:
        """End the streams whose last command is more than STREAM_GAP_S before ``t``."""
        closed: list[Movement] = []
        for stream in self.open.values():
            if t - stream.last > STREAM_GAP_S:
                break
        else:
            return closed  # the usual answer, for every event while a stick moves
        quiet = [c for c, stream in self.open.items() if t - stream.last > STREAM_GAP_S]
        for component in quiet:
            closed += self._end(component, None, EndedBy.PAUSE)
        return closed

    def cut(self, t: float, name: str) -> list[Movement]:
        """Another motion command ``name`` at ``t``: every stream ends, every window is
        cut there."""
        self.other_at, self.other_name = t, name
        self.reshaped = True
        closed: list[Movement] = []
        for component in list(self.open):
            closed += self._end(component, t, EndedBy.OTHER_COMMAND, name)
        for waiting in self.waiting:
            waiting.cut(t, name)
        return closed

    def end(self) -> list[Movement]:
        """The input ended: every open stream ends."""
        closed: list[Movement] = []
        for component in list(self.open):
            closed += self._end(component, None, EndedBy.INPUT_ENDED)
        return closed

    def judged(self, movements: list[Movement]) -> None:
        """Movements judged: they wait no more."""
        done = set(map(id, movements))
        self.waiting = [m for m in self.waiting if id(m) not in done]

    def _end(self, component: str, t: float | None, why: EndedBy, name: str = "") -> list[Movement]:
        stream = self.open.pop(component)
        self.reshaped = True
        movement = stream.movement
        if movement is None:
            return []
        stream.movement = None
        if t is None:
            movement.close(movement.last + HOLD_S, why)
        else:
            movement.cut(t, name)
        self.waiting.append(movement)
        return [movement]

    def _retire(self, stream: StickStream) -> None:
        movement = stream.movement
        if movement is not None:
            stream.movement = None
            self.waiting.append(movement)
            self.reshaped = True

    def starts(self) -> list[float]:
        """The first command of every movement under way or awaiting its judgement."""
        out = [m.start for m in self.waiting]
        out += [s.movement.start for s in self.open.values() if s.movement is not None]
        return out
