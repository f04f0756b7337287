"""The stick streams' judgements over time: movements against the feedback, the stop after."""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from analyzer.analysis.findings import ResponseFinding
from analyzer.analysis.motion_fit import LAG_MAX_S
from analyzer.analysis.rates import Cut, CutBy, judge_cadence, judge_movement, judge_stop
from analyzer.analysis.sample_window import SampleWindow
from analyzer.analysis.samples import MOTOR_YAW, PITCH, Sample
from analyzer.analysis.streams import HOLD_S, STREAM_GAP_S, Movement, Streams
from analyzer.analysis.targets import STILL_DEG
from analyzer.feedback_track import FEEDBACK_PERIOD_S

STOP_GRACE_S = 0.5  # the gimbal may coast this long after the last gimbal_control
STOP_OBSERVE_S = 2.0  # then it is watched this long for movement
STOP_LONGEST_S = 4.0  # or longer, while too few feedback messages came to tell
# A whole message can come this late with no warning (its segments together): its time
# may be this much later than it measured.
UNSEEN_LATE_S = 0.3
# The samples of this long before now are kept: whether the gimbal was still before a
# movement (after another command) is seen in them.
LOOKBACK_S = LAG_MAX_S + 2.0


@dataclass
class _StopCheck:
    """After a movement the stick is centred: the gimbal is watched until ``until``
    (sooner when ``cut`` by the stick or another command)."""

    movement: Movement
    until: float
    cut: bool = False


class StickJudge:
    """The gimbal_control side of the response analysis (``ResponseAnalyzer`` feeds it):
    streams cut into movements, each judged once its feedback window is over, and the
    gimbal watched while the stick is centred. ``samples`` are the analysis' attitude
    samples; ``tolerance`` the degrees below which motion is not judged."""

    def __init__(self, samples: SampleWindow, tolerance: float, late: float) -> None:
        self.samples = samples
        self.tolerance = tolerance
        self.late = late  # without feedback, a judgement waits this long past its window
        self.streams = Streams()
        self._stops: list[_StopCheck] = []

    def due(self) -> float:
        """The earliest time at which ``settle`` without a sample judges or ends something."""
        streams, late = self.streams, self.late
        due = min((s.last + STREAM_GAP_S for s in streams.open.values()), default=math.inf)
        for movement in streams.waiting:
            assert movement.window_end is not None
            due = min(due, movement.window_end + late)
        for stop in self._stops:
            due = min(due, stop.until + late)
        return due

    @property
    def active(self) -> bool:
        """Something is open or waits for its judgement."""
        streams = self.streams
        return bool(streams.open or streams.waiting or self._stops)

    def command(
        self,
        t: float,
        component: str,
        pan: float,
        tilt: float,
        target_met: Callable[[], bool] | None = None,
    ) -> float | None:
        """One gimbal_control; the first command of its movement when the stick is off
        centre (the motion a limit finding would name), else None. ``target_met``, asked
        when a movement starts: the last other motion command was a target the gimbal is
        at (nothing left to do)."""
        moving = pan != 0 or tilt != 0
        if moving and self._stops:
            for stop in self._stops:
                if stop.movement.component == component:
                    stop.until, stop.cut = min(stop.until, t), True  # the stick moved again
                    self.streams.reshaped = True
        closed = self.streams.command(t, component, pan, tilt)
        if closed:
            self._stopped(closed)
        stream = self.streams.open.get(component) if moving else None
        if stream is not None and stream.movement is not None:
            movement = stream.movement
            if movement.start == t and not self._free_before(
                movement, target_met is not None and target_met()
            ):
                movement.free_from = t
            return movement.start
        return None

    def _free_before(self, movement: Movement, target_met: bool) -> bool:
        """Nothing the movement's commands do not tell was turning the gimbal when it
        started: neither another motion command (but a target the gimbal is at), nor the
        stream's own commands older than those it carries. So when no such command came,
        when the stream's commands it carries took over a lag after the other one, or when
        two feedback messages in a row since showed the gimbal still."""
        other = None if target_met else movement.other_before
        own = movement.own_before
        if own is not None:
            own += HOLD_S  # its speeds held on that long
            reference = self._reference(movement.start)
            if reference is not None and reference.time >= own + LAG_MAX_S:
                own = None  # over before the message the fit starts from
        since = max((t for t in (other, own) if t is not None), default=None)
        if since is None:
            return True
        if (
            other is not None
            and own is None
            and any(other <= c.time <= movement.start - LAG_MAX_S for c in movement.prior)
        ):
            return True
        seen = [s for s in self.samples.between(since + LAG_MAX_S, movement.start) if not s.late]
        return any(
            all(abs(b.value(axis) - a.value(axis)) < STILL_DEG for axis in (PITCH, MOTOR_YAW))
            for a, b in itertools.pairwise(seen)
        )

    def interrupt(self, t: float, name: str) -> list[ResponseFinding]:
        """Another motion command at ``t``: every stream ends; what waits is judged once
        its window, which reaches on by the longest lag, is over."""
        out: list[ResponseFinding] = []
        self.streams.cut(t, name)
        for stop in self._stops:
            stop.until, stop.cut = min(stop.until, t), True
            out += self._judge_stop(stop)
        self._stops = []
        return out

    def settle(self, t: float, sample: Sample | None) -> list[ResponseFinding]:
        """Judge what has had its time; ``sample`` is a new attitude sample at ``t``."""
        out: list[ResponseFinding] = []
        streams = self.streams
        if streams.open:
            closed = streams.end_quiet(t)
            if closed:
                self._stopped(closed)
        late = 0.0 if sample is not None else self.late
        if streams.waiting:
            judged: list[Movement] = []
            for movement in streams.waiting:
                end = movement.window_end
                assert end is not None
                if sample is not None and not sample.late and t >= end:
                    out += self._judge_movement(movement, t)
                elif t > end + self.late:  # no good message after the window
                    out += self._judge_movement(movement, None, self._stopped_at(end))
                else:
                    continue
                judged.append(movement)
            streams.judged(judged)
        if self._stops:
            watching: list[_StopCheck] = []
            for stop in self._stops:
                if t > stop.until + late:
                    found = self._judge_stop(stop)
                    out += found
                    longest = stop.movement.stopped_at + STOP_GRACE_S + STOP_LONGEST_S
                    if not found and not stop.cut and stop.until < longest:
                        stop.until += FEEDBACK_PERIOD_S  # messages were lost: watch on
                        watching.append(stop)
                else:
                    watching.append(stop)
            self._stops = watching
        return out

    def close(self, ended_at: float) -> list[ResponseFinding]:
        """The end of the input (at ``ended_at``): every stream ends, everything is judged."""
        out: list[ResponseFinding] = []
        self._stopped(self.streams.end())
        last = self.samples.last
        waiting = list(self.streams.waiting)
        for movement in waiting:
            cut = Cut(CutBy.INPUT_ENDED, ended_at)
            if last is None or last.time < max(ended_at - self.late, movement.start):
                # the feedback had gone silent before: that is what cut it
                cut = Cut(CutBy.FEEDBACK_STOPPED, last.time if last is not None else ended_at)
            out += self._judge_movement(movement, None, cut)
        self.streams.judged(waiting)
        for stop in self._stops:
            out += self._judge_stop(stop)
        self._stops = []
        return out

    def pending(self) -> list[float]:
        """The times of the findings still to come (the samples they need start there)."""
        return [*self.streams.starts(), *(stop.movement.stopped_at for stop in self._stops)]

    def _stopped(self, movements: list[Movement]) -> None:
        """Movements the stick came back from: the gimbal must then hold still."""
        for movement in movements:
            if movement.ended_by is not None and movement.ended_by.centred:
                until = movement.stopped_at + STOP_GRACE_S + STOP_OBSERVE_S
                self._stops.append(_StopCheck(movement, until))
                self.streams.reshaped = True

    def _judge_movement(
        self, movement: Movement, upto: float | None, cut: Cut | None = None
    ) -> list[ResponseFinding]:
        """A stick movement against the feedback up to ``upto`` (a sample's time at or
        after its window's end; None: up to the window's end, which ``cut`` says the
        feedback did not reach), and its stream's cadence."""
        end = movement.window_end
        assert end is not None
        last = end if upto is None or movement.cut_short else max(upto, end)
        before = self._reference(movement.start)
        inside = self.samples.between(movement.start, last)
        judged = judge_movement(
            movement, before, inside, self.tolerance, free_from=movement.free_from, cut=cut
        )
        movement.followed = judged.followed  # what the stop check takes as explained
        rate = judged.finding
        cadence = judge_cadence(movement, rate.verdict)
        if cadence is None:
            return [rate]
        movement.stream.cadence_said = True  # a stream's cadence is said once
        return [rate, cadence]

    def _stopped_at(self, end: float) -> Cut | None:
        """Why no message came to close a window that ended at ``end``: the feedback
        stopped (at its last message), or None when messages came but dated late."""
        last = self.samples.last
        if last is not None and last.time >= end:
            return None
        return Cut(CutBy.FEEDBACK_STOPPED, last.time if last is not None else end)

    def _reference(self, t: float) -> Sample | None:
        """The last sample at or before ``t`` not dated late (one measured when dated)."""
        for sample in reversed(self.samples.between(t - LOOKBACK_S, t)):
            if not sample.late:
                return sample
        return self.samples.before(t)

    def _judge_stop(self, stop: _StopCheck) -> list[ResponseFinding]:
        """Still once the stick came back and its grace is over, beyond what the
        movement's commands, followed as late as its fit found, still explain?"""
        movement = stop.movement
        end = movement.stopped_at
        # A message dated late (its segments came far apart) measured earlier: left out.
        after = [s for s in self.samples.between(end + STOP_GRACE_S, stop.until) if not s.late]
        follows = _follows(movement)
        if follows is not None and movement.followed is not None:
            # What the fit explains is taken out: from the last message before the grace
            # ends, when it was surely measured after the gimbal followed the stop.
            reference = self.samples.before(end + STOP_GRACE_S)
            after_stop = end + movement.followed[0] + UNSEEN_LATE_S
            if reference is not None and reference.time >= after_stop and not reference.late:
                after = [reference, *after]
        found = judge_stop("gimbal_control", end, after, self.tolerance, follows)
        return [] if found is None else [found]


def _follows(movement: Movement) -> Callable[[str, list[float]], list[float]] | None:
    """The angles (per feedback axis, at times) the movement's commands explain, followed
    with the lag and ratios its fit found; None without a fit."""
    if movement.followed is None:
        return None
    lag, ratios = movement.followed
    motion = movement.motion()
    index = {MOTOR_YAW: 0, PITCH: 1}

    def follows(axis: str, times: list[float]) -> list[float]:
        i = index[axis]
        if i not in ratios:
            return [0.0] * len(times)
        angles: list[float] = (ratios[i] * motion.axis_at(np.array(times) - lag, i)).tolist()
        return angles

    return follows
