"""The check against a simulated gimbal in virtual time: the same steps and runner, no waiting."""

from __future__ import annotations

from collections.abc import Callable

from analyzer.analysis.stage import Analysis
from analyzer.check.judge import Limits, StepResult
from analyzer.check.observer import Observer
from analyzer.check.runner import CheckRunner
from analyzer.check.steps import CheckStep, Options
from analyzer.pipeline import Pipeline
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.ids import CONTROL_ID
from analyzer.protocol.types import CanFrame, Event
from analyzer.sim.engine import SimConfig, SimulatedGimbal

START = 1_715_680_800.0  # 2024-05-14 10:00 UTC: the time the bench's clock starts at
TICK_S = 0.01  # the virtual clock's step
CHANNEL = "sim"


class _Observer(Observer):
    """The check's observer whose waiting lets the bench's virtual time pass."""

    def __init__(self, bench: SimulatedBench, *, keep_events: bool) -> None:
        super().__init__(keep_events=keep_events)
        self._bench = bench

    def wait(self, done: Callable[[], bool], until: float) -> bool:
        return self._bench.run(done, until)


class SimulatedBench:
    """A simulated gimbal on a virtual CAN bus, captured by the check's pipeline (the
    response analysis, then the observer), in virtual time.

    It is at once the runner's link (``send``, ``note``) and its clock (``time``,
    ``monotonic``, ``sleep``); ``observer`` is the runner's observer, whose ``wait``
    runs the bench until what it waits for holds. ``frames`` keeps the bus, commands
    and feedback, as a capture of it would (for ``analyze``)."""

    def __init__(
        self, config: SimConfig | None = None, limits: Limits | None = None, start: float = START
    ) -> None:
        self.start = start
        self.now = start
        self._ticks = 0
        self.gimbal = SimulatedGimbal(start, config)
        self._decoder = ProtocolDecoder()  # the gimbal's own, for the commands it receives
        self.limits = limits or Limits()
        self.observer = _Observer(self, keep_events=True)
        self.pipeline = Pipeline([self.observer], stages=Analysis(self.limits.settings).stages())
        self.frames: list[CanFrame] = []

    # -- the link --------------------------------------------------------------------------

    def send(self, data: bytes) -> float:
        return self.send_frame(CONTROL_ID, data)

    def send_frame(self, can_id: int, data: bytes) -> float:
        """A frame of the ground station's: a command, or UAV status the gimbal takes in."""
        frame = CanFrame(self.now, can_id, data, channel=CHANNEL)
        self._on_bus([frame])
        for event in self._decoder.feed(frame):
            self.gimbal.handle(event, self.now)
        return self.now

    def note(self, event: Event) -> None:
        self.pipeline.add_events([event])

    # -- the clock -------------------------------------------------------------------------

    def time(self) -> float:
        return self.now

    def monotonic(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.run(lambda: False, self.now + seconds)

    # -- time passing ----------------------------------------------------------------------

    def run(self, done: Callable[[], bool], until: float) -> bool:
        """Let time pass, the capture delivered at every tick, until ``done()`` holds (True)
        or ``until`` (False)."""
        while True:
            self.pipeline.deliver(self.now)
            if done():
                return True
            if self.now >= until - 1e-9:
                return False
            self._ticks += 1
            self.now = self.start + self._ticks * TICK_S
            sent = self.gimbal.poll(self.now)
            if sent:
                self._on_bus([CanFrame(self.now, i, d, channel=CHANNEL) for i, d in sent])

    def _on_bus(self, frames: list[CanFrame]) -> None:
        self.frames.extend(frames)
        self.pipeline.feed(frames)

    def finish(self) -> list[Event]:
        """The end of the capture: the analysis closes; every event the capture made."""
        self.pipeline.finish(self.now)
        return self.observer.events

    # -- the check -------------------------------------------------------------------------

    def check(
        self, steps: tuple[CheckStep, ...], options: Options | None = None
    ) -> list[StepResult]:
        """Run the check's ``steps`` on this bench, as ``gimbal-analyzer check`` would."""
        runner = CheckRunner(
            self,
            self.observer,
            self.limits,
            options or Options(),
            lambda _: None,
            lambda _: None,
            clock=self,
        )
        return runner.run(steps)
