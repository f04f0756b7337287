"""A pipeline sink that keeps what the check waits for: attitude samples, findings, damage."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from analyzer.analysis.samples import Sample, sample_from
from analyzer.pipeline import Batch
from analyzer.protocol.types import (
    CRC_MISMATCH,
    INCOMPLETE,
    TOPIC_ANALYSIS_RESPONSE,
    TOPIC_CHECK_STEPS,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_GIMBAL_RANGING,
    Event,
)

DAMAGED = frozenset({CRC_MISMATCH, INCOMPLETE})  # as the response analysis counts crc_errors


class Observer:
    """Sink of the check's capture: the main thread reads, the capture thread writes.

    Findings are the /analysis/response events of the pipeline's ResponseAnalyzer stage,
    the very ones the recording holds. ``keep_events`` keeps every event (for --report).
    """

    keeps_items = False

    def __init__(self, *, keep_events: bool = False) -> None:
        self.samples: list[Sample] = []
        self.feedback_times: list[float] = []
        self.damaged_times: list[float] = []
        self.findings: list[dict[str, Any]] = []
        self.events: list[Event] = []
        self.keep_events = keep_events
        self.steps_seen = 0  # /check/steps events that went through the pipeline
        self.commands_until = 0.0  # time of the newest command that went through it
        self.closed = False
        self._changed = threading.Condition()

    def handle(self, batch: Batch) -> None:
        with self._changed:
            for event in batch.events:
                topic = event.topic
                if topic == TOPIC_GIMBAL_ATTITUDE:
                    self.feedback_times.append(event.time)
                    sample = sample_from(event.time, event.fields)
                    if sample is not None:
                        self.samples.append(sample)
                elif topic == TOPIC_GIMBAL_RANGING:
                    self.feedback_times.append(event.time)
                elif topic == TOPIC_ANALYSIS_RESPONSE:
                    self.findings.append(event.to_dict())
                elif topic == TOPIC_COMMAND:
                    self.commands_until = max(self.commands_until, event.time)
                elif topic == TOPIC_CHECK_STEPS:
                    self.steps_seen += 1
                elif topic == TOPIC_DIAGNOSTICS and event.fields.get("kind") in DAMAGED:
                    self.damaged_times.append(event.time)
                if self.keep_events:
                    self.events.append(event)
            self._changed.notify_all()

    def close(self) -> None:
        with self._changed:
            self.closed = True
            self._changed.notify_all()

    # -- the main thread's side ----------------------------------------------------------

    def wait(self, done: Callable[[], bool], until: float) -> bool:
        """Wait (monotonic clock) until ``done()`` holds or ``until``; True when it held.

        ``done`` runs with the lock held, after every batch of the capture."""
        with self._changed:
            while True:
                if done():
                    return True
                left = until - time.monotonic()
                if left <= 0 or self.closed:
                    return done()
                self._changed.wait(min(left, 0.1))

    def latest(self) -> Sample | None:
        with self._changed:
            return self.samples[-1] if self.samples else None

    def samples_between(self, start: float, end: float) -> list[Sample]:
        with self._changed:
            return [s for s in self.samples if start < s.time <= end]

    def findings_for(self, command: str, first: float, last: float) -> list[dict[str, Any]]:
        """The findings about ``command`` sent from ``first`` to ``last`` (the analysis dates
        a finding with its command's time: a burst's first, its stop's for ``stop``)."""
        with self._changed:
            return [
                f
                for f in self.findings
                if f.get("command") == command
                and first - 1e-6 <= float(f.get("time", 0.0)) <= last + 1e-6
            ]

    def feedback_in(self, start: float, end: float) -> list[float]:
        with self._changed:
            return [t for t in self.feedback_times if start <= t <= end]

    def damaged_in(self, start: float, end: float) -> int:
        with self._changed:
            return sum(1 for t in self.damaged_times if start <= t <= end)
