"""Runs the steps on the live link: sends, waits for the gimbal, collects the verdicts in order."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from analyzer import wall_clock
from analyzer.analysis.samples import MOTOR_YAW, PITCH, Sample
from analyzer.analysis.targets import SETTLED_S, STILL_DEG
from analyzer.analysis.yaw_geometry import angle_error, psi_offset
from analyzer.check.judge import Evidence, Limits, StepResult, judge, required_check
from analyzer.check.link import CheckLink
from analyzer.check.observer import Observer
from analyzer.check.steps import REPEAT_S, Attitude, Hold, Listen, Options, Plan, Send, Step
from analyzer.protocol.codec import encode_command
from analyzer.protocol.response_fields import CHECK_PICTURE
from analyzer.protocol.types import TOPIC_CHECK_STEPS, Event

FIRST_FEEDBACK_WAIT_S = 2.0  # before the first step: wait this long for the gimbal to speak
MIN_SETTLE_WAIT_S = 1.5  # a move is not judged still before this much time has passed
AFTER_DEADLINE_S = 0.8  # a verdict comes with the first feedback after the time allowed
CENTRE_NAME = "forward"
# A verdict from the picture comes later: the camera's frames reach the recorder after the
# telemetry, and a zoom is judged once it could have settled.
PICTURE_WAIT_S = 3.0


@dataclass
class _Running:
    """A step that has sent everything and may still wait for its findings."""

    index: int
    step: Step
    plan: Plan
    started_at: float
    ended_at: float = 0.0
    judged: list[tuple[Send | Hold, float, float]] = field(default_factory=list)


def encode(name: str, params: dict[str, Any]) -> bytes:
    return encode_command(name, **params)


class CheckRunner:
    """Drives the steps over ``link``; ``report`` gets each step's result, in step order.

    Verdicts come from the findings of the capture's ResponseAnalyzer stage (the
    ``observer`` sees them). A move's finding comes when the time allowed has passed, or
    as soon as the next motion command shows that it is over: so a step that has
    reached its target and is still moves on, and is reported when its finding arrives.
    """

    def __init__(
        self,
        link: CheckLink,
        observer: Observer,
        limits: Limits,
        options: Options,
        report: Callable[[StepResult], None],
        notice: Callable[[str], None] = print,
    ) -> None:
        self.link = link
        self.observer = observer
        self.limits = limits
        self.options = options
        self.report = report
        self.notice = notice
        self.results: list[StepResult] = []
        self._pending: list[_Running] = []
        self.centred: bool | None = None

    @property
    def allowed_s(self) -> float:
        return self.limits.settings.time_allowed_s

    # -- the sequence ----------------------------------------------------------------------

    def run(self, steps: tuple[Step, ...]) -> list[StepResult]:
        first = time.monotonic() + FIRST_FEEDBACK_WAIT_S
        if not self.observer.wait(lambda: bool(self.observer.samples), first):
            self.notice(
                f"no attitude feedback in {FIRST_FEEDBACK_WAIT_S:g} s: is the gimbal on this "
                "link and powered? The steps go on and fail as 'no feedback'"
            )
        for index, step in enumerate(steps, 1):
            plan = step.plan(self.attitude(), self.options)
            running = _Running(index, step, plan, wall_clock.now())
            for action in plan.actions:
                self._act(action, running)
                self._flush(force=False)  # an earlier step decided by this action's command
            running.ended_at = wall_clock.now()
            self._pending.append(running)
            self._flush(force=False)
        self.centre(wait=True)
        deadline = time.monotonic() + self.allowed_s + AFTER_DEADLINE_S
        if any(required_check(a) == CHECK_PICTURE for r in self._pending for a, _, _ in r.judged):
            deadline += PICTURE_WAIT_S
        self.observer.wait(self._all_decided, deadline)
        self._flush(force=True)
        return self.results

    def attitude(self) -> Attitude:
        sample = self.observer.latest()
        if sample is None:
            return Attitude()
        return Attitude(sample.pitch, sample.motor_yaw, psi_offset(sample))

    def centre(self, *, wait: bool) -> None:
        """Speeds to 0 first, then ``forward``; with ``wait``, until the feedback shows it."""
        self.link.send(encode("gimbal_control", {"pan_speed_dps": 0.0, "tilt_speed_dps": 0.0}))
        sent = self.link.send(encode(CENTRE_NAME, {}))
        if wait:
            goals = ((PITCH, 0.0), (MOTOR_YAW, 0.0))
            until = time.monotonic() + self.allowed_s + AFTER_DEADLINE_S
            self.centred = self.observer.wait(lambda: self._reached(goals, sent), until)

    # -- actions ---------------------------------------------------------------------------

    def _act(self, action: Send | Hold | Listen, running: _Running) -> None:
        if isinstance(action, Listen):
            self._sleep(action.seconds)
        elif isinstance(action, Hold):
            self._hold(action, running)
        else:
            self._send(action, running)

    def _sleep(self, seconds: float) -> None:
        self.observer.wait(lambda: False, time.monotonic() + seconds)

    def _send(self, action: Send, running: _Running) -> None:
        sent = self.link.send(encode(action.name, action.params))
        number = len(running.judged)
        if action.judged:
            running.judged.append((action, sent, sent))
        until = time.monotonic() + self.allowed_s + AFTER_DEADLINE_S
        if action.goals:

            def over() -> bool:
                decided = action.judged and self._decided(running, number)
                return decided or self._reached(action.goals, sent) or self._still(action, sent)

            self.observer.wait(over, until)
        elif action.check and action.check != CHECK_PICTURE:
            self.observer.wait(lambda: self._decided(running, number), until)
        # a verdict from the picture needs what comes after (the zoom's stop): the step is
        # reported once it comes
        if action.pause:
            self._sleep(action.pause)

    def _hold(self, action: Hold, running: _Running) -> None:
        data = encode(
            "gimbal_control", {"pan_speed_dps": action.pan_dps, "tilt_speed_dps": action.tilt_dps}
        )
        first = last = 0.0
        next_at = time.monotonic()
        for count in range(action.count):
            last = self.link.send(data)
            first = first or last
            next_at += REPEAT_S
            if count + 1 < action.count:
                time.sleep(max(0.0, next_at - time.monotonic()))
        stop = self.link.send(
            encode("gimbal_control", {"pan_speed_dps": 0.0, "tilt_speed_dps": 0.0})
        )
        number = len(running.judged)
        running.judged.append((action, first, stop))
        # The analysis watches a while after the stop, well within the time allowed.
        until = time.monotonic() + self.allowed_s + AFTER_DEADLINE_S
        self.observer.wait(lambda: self._decided(running, number), until)

    # -- what the feedback shows -----------------------------------------------------------

    def _after(self, t: float) -> list[Sample]:
        return [s for s in self.observer.samples if s.time > t]

    def _reached(self, goals: tuple[tuple[str, float], ...], t: float) -> bool:
        """The last two samples after ``t`` are within the tolerance of every goal."""
        recent = self._after(t)[-2:]
        tolerance = self.limits.settings.tolerance_deg
        return len(recent) == 2 and all(
            abs(angle_error(axis, target, s)) <= tolerance for s in recent for axis, target in goals
        )

    def _still(self, action: Send, t: float) -> bool:
        """No goal axis has moved for SETTLED_S (the analysis' own rule for a final answer)."""
        if wall_clock.now() - t < MIN_SETTLE_WAIT_S:
            return False
        after = self._after(t)
        if len(after) < 3:
            return False
        last = after[-1]
        for s in reversed(after):
            if any(abs(s.value(a) - last.value(a)) >= STILL_DEG for a, _ in action.goals):
                return False
            if last.time - s.time >= SETTLED_S + 0.1:
                return True
        return False

    def _decided(self, running: _Running, number: int) -> bool:
        if number >= len(running.judged):
            return False
        action, first, last = running.judged[number]
        name = action.name if isinstance(action, Send) else "gimbal_control"
        wanted = required_check(action)
        return any(f.get("check") == wanted for f in self.observer.findings_for(name, first, last))

    def _all_decided(self) -> bool:
        return all(self._decided(r, n) for r in self._pending for n in range(len(r.judged)))

    # -- results ---------------------------------------------------------------------------

    def _flush(self, *, force: bool) -> None:
        """Report the finished steps whose findings are all in, in order (all with ``force``)."""
        while self._pending:
            running = self._pending[0]
            if not force and not all(self._decided(running, n) for n in range(len(running.judged))):
                return
            self._pending.pop(0)
            self._finish(running)

    def _finish(self, running: _Running) -> None:
        observer = self.observer
        findings = {}
        for number, (action, first, last) in enumerate(running.judged):
            name = action.name if isinstance(action, Send) else "gimbal_control"
            findings[number] = observer.findings_for(name, first, last)
        start, end = running.started_at, running.ended_at
        evidence = Evidence(
            plan=running.plan,
            started_at=start,
            ended_at=end,
            judged=running.judged,
            samples=observer.samples_between(start - 1.0, end),
            feedback_times=observer.feedback_in(start, end),
            damaged=observer.damaged_in(start, end),
            findings=findings,
        )
        verdict, detail, figures, lines = judge(evidence, self.limits)
        result = StepResult(
            running.step.name,
            verdict,
            detail,
            figures,
            running.index,
            start,
            end - start,
            lines,
        )
        self.results.append(result)
        self.link.note(Event(TOPIC_CHECK_STEPS, wall_clock.now(), "check", result.fields()))
        self.report(result)
