"""Runs a SimulatedGimbal on a link in real time: receive, decode, act, send, report."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.types import TOPIC_COMMAND, TOPIC_DIAGNOSTICS, Event
from analyzer.sim.engine import SimulatedGimbal, describe_command
from analyzer.sim.transports import SimulatedLink

MAX_WAIT = 0.05  # longest sleep between checks of the stop flag
REPEAT_QUIET_S = 1.0  # a command repeated unchanged is reported at most this often
STATUS_EVERY = 5.0


class SimulatorRunner:
    """The simulator's real-time loop; ``run()`` returns on ``stop()``, timeout or link error."""

    def __init__(
        self,
        gimbal: SimulatedGimbal,
        link: SimulatedLink,
        *,
        log: Callable[[str], None] | None = None,
        clock: Callable[[], float] = time.monotonic,
        status_every: float | None = STATUS_EVERY,
    ) -> None:
        self.gimbal = gimbal
        self.link = link
        self.log = log
        self.clock = clock
        self.status_every = status_every
        self.decoder = ProtocolDecoder()
        self.received: list[Event] = []  # events decoded from what the simulator received
        self.keep_received = False
        self._stop = threading.Event()
        self._last_raw = ""
        self._last_said = -1e9
        self._repeats = 0

    def stop(self) -> None:
        self._stop.set()

    def run(self, duration: float | None = None) -> None:
        start = self.clock()
        end = None if duration is None else start + duration
        next_status = start + (self.status_every or 0.0)
        while not self._stop.is_set():
            now = self.clock()
            if end is not None and now >= end:
                break
            for can_id, data in self.gimbal.poll(now):
                self.link.send(can_id, data)
            now = self.clock()
            if self.status_every and now >= next_status:
                next_status = now + self.status_every
                self._say(now, f"{self.gimbal.state_line()} | {self.gimbal.counts_line()}")
            wait = min(MAX_WAIT, max(0.0, self.gimbal.next_time() - now))
            if end is not None:
                wait = min(wait, max(0.0, end - now))
            for item in self.link.receive(wait):
                for event in self.decoder.feed(item):
                    self._handle(event, self.clock())

    def _handle(self, event: Event, now: float) -> None:
        if self.keep_received:
            self.received.append(event)
        acted = self.gimbal.handle(event, now)
        if event.topic == TOPIC_COMMAND:
            raw = str(event.fields.get("raw", ""))
            if raw == self._last_raw and now - self._last_said < REPEAT_QUIET_S:
                self._repeats += 1
                return
            if self._repeats:
                self._say(now, f"rx ... previous command repeated {self._repeats} more time(s)")
            self._last_raw, self._last_said, self._repeats = raw, now, 0
            note = "" if acted else "  [ignored]"
            warn = f"  warnings: {'; '.join(event.warnings)}" if event.warnings else ""
            self._say(now, f"rx {describe_command(event.fields)}{note}{warn}")
        elif event.topic == TOPIC_DIAGNOSTICS:
            kind, detail = event.fields.get("kind"), event.fields.get("detail")
            self._say(now, f"rx problem: {kind}: {detail}")

    def _say(self, now: float, text: str) -> None:
        if self.log is not None:
            self.log(f"[{now - self.gimbal.start:7.2f}] {text}")
