"""The stick streams' judgements over time: movements against the feedback, the stop after."""

from __future__ import annotations

from dataclasses import dataclass

from analyzer.analysis.findings import Finding
from analyzer.analysis.rates import judge_cadence, judge_movement, judge_stop
from analyzer.analysis.sample_window import SampleWindow
from analyzer.analysis.samples import Sample
from analyzer.analysis.streams import Movement, Streams

STOP_GRACE_S = 0.5  # the gimbal may coast this long after the last gimbal_control
STOP_OBSERVE_S = 2.0  # then it is watched this long for movement


@dataclass
class _StopCheck:
    """After a movement the stick is centred: the gimbal is watched until ``until``."""

    movement: Movement
    until: float


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

    @property
    def active(self) -> bool:
        """Something is open or waits for its judgement."""
        streams = self.streams
        return bool(streams.open or streams.waiting or self._stops)

    def command(self, t: float, component: str, pan: float, tilt: float) -> float | None:
        """One gimbal_control; the first command of its movement when the stick is off
        centre (the motion a limit finding would name), else None."""
        if pan != 0 or tilt != 0:
            for stop in self._stops:
                if stop.movement.component == component:
                    stop.until = min(stop.until, t)  # the stick moved again
        self._stopped(self.streams.command(t, component, pan, tilt))
        stream = self.streams.open.get(component)
        if (pan != 0 or tilt != 0) and stream is not None and stream.movement is not None:
            return stream.movement.start
        return None

    def interrupt(self, t: float, name: str) -> list[Finding]:
        """Another motion command at ``t``: every stream ends, what waits is judged on
        what came before it."""
        out: list[Finding] = []
        self.streams.cut(t, f"{name} came")
        for movement in self.streams.waiting:
            out += self._judge_movement(movement, None)
        self.streams.waiting = []
        for stop in self._stops:
            stop.until = min(stop.until, t)
            out += self._judge_stop(stop)
        self._stops = []
        return out

    def settle(self, t: float, sample: Sample | None) -> list[Finding]:
        """Judge what has had its time; ``sample`` is a new attitude sample at ``t``."""
        out: list[Finding] = []
        streams = self.streams
        if streams.open:
            closed = streams.end_quiet(t)
            if closed:
                self._stopped(closed)
        late = 0.0 if sample is not None else self.late
        if streams.waiting:
            waiting: list[Movement] = []
            for movement in streams.waiting:
                end = movement.window_end
                assert end is not None
                if sample is not None and t >= end:
                    out += self._judge_movement(movement, t)
                elif t > end + self.late:
                    out += self._judge_movement(movement, None)
                else:
                    waiting.append(movement)
            streams.waiting = waiting
        if self._stops:
            watching: list[_StopCheck] = []
            for stop in self._stops:
                if t > stop.until + late:
                    out += self._judge_stop(stop)
                else:
                    watching.append(stop)
            self._stops = watching
        return out

    def close(self) -> list[Finding]:
        """The end of the input: every stream ends, everything is judged."""
        out: list[Finding] = []
        self._stopped(self.streams.end())
        for movement in self.streams.waiting:
            out += self._judge_movement(movement, None)
        self.streams.waiting = []
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
            if movement.ended_by in ("zeros", "pause"):
                until = movement.stopped_at + STOP_GRACE_S + STOP_OBSERVE_S
                self._stops.append(_StopCheck(movement, until))

    def _judge_movement(self, movement: Movement, upto: float | None) -> list[Finding]:
        """A stick movement against the feedback up to ``upto`` (a sample's time at or
        after its window's end; None: up to the window's end), and its stream's cadence."""
        end = movement.window_end
        assert end is not None
        last = end if upto is None or movement.cut_short else max(upto, end)
        before = self.samples.before(movement.start)
        inside = self.samples.between(movement.start, last)
        rate = judge_movement(movement, before, inside, self.tolerance)
        cadence = judge_cadence(movement, rate.verdict)
        return [rate] if cadence is None else [rate, cadence]

    def _judge_stop(self, stop: _StopCheck) -> list[Finding]:
        end = stop.movement.stopped_at
        after = self.samples.between(end + STOP_GRACE_S, stop.until)
        found = judge_stop("gimbal_control", end, after, self.tolerance)
        return [] if found is None else [found]
