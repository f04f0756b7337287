"""Runs the steps on the live link: sends, waits for the gimbal, collects the verdicts in order."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

from analyzer.analysis.findings import OBEYED, UNKNOWN
from analyzer.analysis.samples import Sample
from analyzer.analysis.yaw_geometry import psi_offset
from analyzer.check.align import (
    WALL_CLOCK,
    Clock,
    Goals,
    at_attitude,
    bring_to,
    centre,
    describe,
    stopped,
    time_needed,
)
from analyzer.check.figures import longest_silence
from analyzer.check.judge import (
    Evidence,
    Limits,
    StepResult,
    judge,
    measure,
    required_checks,
    undecided,
)
from analyzer.check.observer import Observer
from analyzer.check.steps import REPEAT_S, Attitude, CheckStep, Hold, Listen, Options, Plan, Send
from analyzer.feedback_track import GAP_THRESHOLD_S
from analyzer.protocol.check_fields import FAIL
from analyzer.protocol.codec import encode_command
from analyzer.protocol.response_fields import CHECK_PICTURE
from analyzer.protocol.types import TOPIC_CHECK_STEPS, Event

FIRST_FEEDBACK_WAIT_S = 2.0  # before the first step: wait this long for the gimbal to speak
# A step the feedback did not allow to be judged (messages lost during it) is run again,
# from its start, at most this many times in all.
MAX_TRIES = 3
AFTER_DEADLINE_S = 0.8  # a verdict comes with the first feedback after the time allowed
# A verdict from the picture comes later: the camera's frames reach the recorder after the
# telemetry, and a zoom is judged once it could have settled.
PICTURE_WAIT_S = 3.0


class StepLink(Protocol):
    """What the runner needs of the link (``analyzer.check.link.CheckLink``): sending a
    command's data bytes (returns the time it went) and recording an event of its own."""

    def send(self, data: bytes) -> float: ...

    def note(self, event: Event) -> None: ...


@dataclass
class _Running:
    """A step that has sent everything and may still wait for its findings."""

    index: int
    step: CheckStep
    plan: Plan
    started_at: float
    ended_at: float = 0.0
    judged: list[tuple[Send | Hold, float, float]] = field(default_factory=list)
    failed: str = ""  # why the step failed before its judged commands (its start)
    before: list[str] = field(default_factory=list)  # why the tries before it were not judged


def encode(name: str, params: dict[str, Any]) -> bytes:
    return encode_command(name, **params)


class CheckRunner:
    """Drives the steps over ``link``; ``report`` gets each step's result, in step order.

    Each step first brings the gimbal to the attitude it starts from
    (``analyzer.check.align.bring_to``), and fails with the reason when it cannot get
    there. Verdicts come from the findings of the capture's ResponseAnalyzer stage (the
    ``observer`` sees them). A move's finding comes when the time allowed has passed, or
    as soon as the next motion command shows that it is over: so a step that has
    reached its target and is still moves on, and is reported when its finding arrives.
    ``clock``: the wall clock, or a simulated one (``analyzer.check.offline``).
    """

    def __init__(
        self,
        link: StepLink,
        observer: Observer,
        limits: Limits,
        options: Options,
        report: Callable[[StepResult], None],
        notice: Callable[[str], None] = print,
        clock: Clock = WALL_CLOCK,
    ) -> None:
        self.link = link
        self.observer = observer
        self.clock = clock
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

    def run(self, steps: tuple[CheckStep, ...]) -> list[StepResult]:
        clock = self.clock
        first = clock.monotonic() + FIRST_FEEDBACK_WAIT_S
        if not self.observer.wait(lambda: bool(self.observer.samples), first):
            self.notice(
                f"no attitude feedback in {FIRST_FEEDBACK_WAIT_S:g} s: is the gimbal on this "
                "link and powered? The steps go on and fail as 'no feedback'"
            )
        for index, step in enumerate(steps, 1):
            before: list[str] = []  # why the tries before could not be judged
            while True:
                running = self._try(index, step)
                why = self._undecided(running) if len(before) + 1 < MAX_TRIES else ""
                if not why:
                    break
                before.append(why)
            running.before = before
            self._pending.append(running)
            self._flush(force=False)
        self.centre(wait=True)
        deadline = clock.monotonic() + self.allowed_s + AFTER_DEADLINE_S
        if any(CHECK_PICTURE in required_checks(a) for r in self._pending for a, _, _ in r.judged):
            deadline += PICTURE_WAIT_S
        self.observer.wait(self._all_decided, deadline)
        self._flush(force=True)
        return self.results

    def _try(self, index: int, step: CheckStep) -> _Running:
        """One run of ``step``: to its start, then its actions."""
        clock = self.clock
        plan = step.plan(self.attitude(), self.options)
        running = _Running(index, step, plan, clock.time())
        running.failed = self._start(plan.start)
        self._flush(force=False)  # an earlier step decided by the start's commands
        running.started_at = clock.time()
        for action in () if running.failed else plan.actions:
            self._act(action, running)
            self._flush(force=False)  # an earlier step decided by this action's command
        running.ended_at = clock.time()
        return running

    def _undecided(self, running: _Running) -> str:
        """Why feedback lost or damaged during the step did not allow it to be judged, as
        far as can be told now ('' when it did, or nothing was lost: a gimbal that did not
        obey is not run again). The findings of targets still to come count as they will
        be: obeyed when the gimbal reached them."""
        if running.failed:
            return running.failed if running.failed.startswith("no feedback") else ""
        if running.plan.skipped or not running.judged:
            return ""
        start, end = running.started_at, running.ended_at
        heard = self.observer.feedback_in(start, end)
        silence, _ = longest_silence(heard, start, end)
        if silence <= GAP_THRESHOLD_S and not self.observer.damaged_in(start, end):
            return ""
        evidence = self._evidence(running)
        pairs: list[tuple[str, str]] = []
        for number, (action, first, _) in enumerate(running.judged):
            found = evidence.findings[number]
            name = action.name if isinstance(action, Send) else "gimbal_control"
            if set(required_checks(action)) <= {f.get("check") for f in found}:
                pairs += [(str(f.get("verdict")), str(f.get("detail"))) for f in found]
            elif not (isinstance(action, Send) and action.goals):
                pairs.append((UNKNOWN, name))
            elif self._reached(action.goals, first):
                pairs.append((OBEYED, ""))
            elif longest_silence(heard, first, end)[0] > GAP_THRESHOLD_S:
                pairs.append((UNKNOWN, name))  # where it went in the silence is not known
        return undecided(evidence, measure(evidence, self.limits), pairs)

    def attitude(self) -> Attitude:
        sample = self.observer.latest()
        if sample is None:
            return Attitude()
        return Attitude(sample.pitch, sample.motor_yaw, psi_offset(sample))

    def centre(self, *, wait: bool) -> None:
        """Speeds to 0 first, then ``forward``; with ``wait``, until the feedback shows it."""
        centred = centre(
            self.link,
            self.observer,
            tolerance_deg=self.limits.settings.tolerance_deg,
            timeout_s=self.allowed_s + AFTER_DEADLINE_S if wait else None,
            clock=self.clock,
        )
        if wait:
            self.centred = centred

    def _start(self, goals: Goals) -> str:
        """Bring the gimbal to a step's start: '' when it is there, else why it is not.

        It has the time a gimbal at the slowest slew that passes (--min-slew) needs for
        the turn, and the time allowed on top; a longer turn than such a gimbal makes in
        the time allowed goes in legs (each command is judged by the analysis too)."""
        if not goals:
            return ""
        tolerance = self.limits.settings.tolerance_deg
        needed = time_needed(goals, self.observer.latest(), self.limits.min_slew_dps)
        arrival = bring_to(
            self.link,
            self.observer,
            goals,
            tolerance_deg=tolerance,
            timeout_s=needed + self.allowed_s,
            clock=self.clock,
            # what a gimbal at its slowest slew that passes turns in the time allowed
            max_turn_deg=self.limits.min_slew_dps * self.allowed_s,
        )
        if arrival.reached:
            return ""
        why = f"the gimbal could not be brought to the step's start ({describe(goals)}): "
        return ("" if arrival.heard else "no feedback: ") + why + arrival.reason

    # -- actions ---------------------------------------------------------------------------

    def _act(self, action: Send | Hold | Listen, running: _Running) -> None:
        if isinstance(action, Listen):
            self._sleep(action.seconds)
        elif isinstance(action, Hold):
            self._hold(action, running)
        else:
            self._send(action, running)

    def _sleep(self, seconds: float) -> None:
        self.observer.wait(lambda: False, self.clock.monotonic() + seconds)

    def _send(self, action: Send, running: _Running) -> None:
        sent = self.link.send(encode(action.name, action.params))
        number = len(running.judged)
        if action.judged:
            running.judged.append((action, sent, sent))
        until = self.clock.monotonic() + self.allowed_s + AFTER_DEADLINE_S
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
        clock = self.clock
        first = last = 0.0
        next_at = clock.monotonic()
        for count in range(action.count):
            last = self.link.send(data)
            first = first or last
            next_at += REPEAT_S
            if count + 1 < action.count:
                clock.sleep(next_at - clock.monotonic())
        stop = self.link.send(
            encode("gimbal_control", {"pan_speed_dps": 0.0, "tilt_speed_dps": 0.0})
        )
        number = len(running.judged)
        running.judged.append((action, first, stop))
        # The analysis watches a while after the stop, well within the time allowed.
        until = clock.monotonic() + self.allowed_s + AFTER_DEADLINE_S
        self.observer.wait(lambda: self._decided(running, number), until)

    # -- what the feedback shows -----------------------------------------------------------

    def _after(self, t: float) -> list[Sample]:
        return [s for s in self.observer.samples if s.time > t]

    def _reached(self, goals: Goals, t: float) -> bool:
        """The last two samples after ``t`` are within the tolerance of every goal."""
        return at_attitude(self._after(t), goals, self.limits.settings.tolerance_deg)

    def _still(self, action: Send, t: float) -> bool:
        """No goal axis has moved for SETTLED_S (the analysis' own rule for a final answer)."""
        axes = [axis for axis, _ in action.goals]
        return stopped(self._after(t), axes, self.clock.time() - t)

    def _decided(self, running: _Running, number: int) -> bool:
        if number >= len(running.judged):
            return False
        action, first, last = running.judged[number]
        name = action.name if isinstance(action, Send) else "gimbal_control"
        given = {f.get("check") for f in self.observer.findings_for(name, first, last)}
        return set(required_checks(action)) <= given

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

    def _evidence(self, running: _Running) -> Evidence:
        """What the step sent and the feedback showed, with the findings come so far."""
        observer = self.observer
        findings = {}
        for number, (action, first, last) in enumerate(running.judged):
            name = action.name if isinstance(action, Send) else "gimbal_control"
            findings[number] = observer.findings_for(name, first, last)
        start, end = running.started_at, running.ended_at
        return Evidence(
            plan=running.plan,
            started_at=start,
            ended_at=end,
            judged=running.judged,
            samples=observer.samples_between(start - 1.0, end),
            feedback_times=observer.feedback_in(start, end),
            damaged=observer.damaged_in(start, end),
            findings=findings,
        )

    def _finish(self, running: _Running) -> None:
        start, end = running.started_at, running.ended_at
        figures: dict[str, Any] = {}
        lines: list[str] = []
        if running.failed:
            verdict, detail = FAIL, running.failed
        else:
            verdict, detail, figures, lines = judge(self._evidence(running), self.limits)
        if running.before:
            tries = len(running.before) + 1
            figures["tries"] = tries
            detail += (
                f"; on try {tries} of {MAX_TRIES}: the feedback did not allow a judgement "
                f"before ({'; '.join(running.before)})"
            )
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
        self.link.note(Event(TOPIC_CHECK_STEPS, self.clock.time(), "check", result.fields()))
        self.report(result)
