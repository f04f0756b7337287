"""The error state of a CAN controller, followed from its error frames, one channel at a time.

The states are those of ISO 11898-1 as SocketCAN names them: error-active (both error
counters below 96), error-warning (96..127), error-passive (128..255) and bus-off (the
controller stopped). A state follows, in order of precedence, from a bus-off class, a
controller problem naming a state (``rx-error-passive``, ``back-to-error-active``, ...),
a restart after bus-off, or the error counters (linux/can/error.h's thresholds). Bus-off
is left only on a restart or a controller problem that names the new state.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from typing import Any

from analyzer.protocol.can_error import CanError

ERROR_ACTIVE = "error-active"
ERROR_WARNING = "error-warning"
ERROR_PASSIVE = "error-passive"
BUS_OFF = "bus-off"
BUS_STATES = (ERROR_ACTIVE, ERROR_WARNING, ERROR_PASSIVE, BUS_OFF)  # index: how bad (level)
LEVELS = {state: level for level, state in enumerate(BUS_STATES)}
WARNING_THRESHOLD = 96  # CAN_ERROR_WARNING_THRESHOLD
PASSIVE_THRESHOLD = 128  # CAN_ERROR_PASSIVE_THRESHOLD
# A /can/bus_state message at least this often (input time) while error frames come in,
# besides one at every change of state or error counters.
REPORT_INTERVAL_S = 1.0


def count_key(name: str) -> str:
    """An error class as a key of the counts (``bus-off`` -> ``bus_off``: plottable paths)."""
    return name.replace("-", "_")


def state_from_counters(tx_errors: int, rx_errors: int) -> str:
    worst = max(tx_errors, rx_errors)
    if worst >= PASSIVE_THRESHOLD:
        return ERROR_PASSIVE
    return ERROR_WARNING if worst >= WARNING_THRESHOLD else ERROR_ACTIVE


def next_state(current: str, error: CanError) -> str:
    """The state after ``error`` on a controller that was in ``current``."""
    if "bus-off" in error.classes:
        return BUS_OFF
    state = current
    if "restarted-after-bus-off" in error.classes:
        state = ERROR_ACTIVE
    named = error.controller
    if "rx-error-passive" in named or "tx-error-passive" in named:
        return ERROR_PASSIVE
    if "rx-error-warning" in named or "tx-error-warning" in named:
        return ERROR_WARNING
    if "back-to-error-active" in named:
        return ERROR_ACTIVE
    if state != BUS_OFF and error.tx_errors is not None and error.rx_errors is not None:
        return state_from_counters(error.tx_errors, error.rx_errors)
    return state


@dataclass
class BusState:
    """One channel's controller: its state since when, error counters, error frames by class."""

    state: str = ERROR_ACTIVE
    since: float | None = None  # time of the error frame that brought the state
    tx_errors: int | None = None
    rx_errors: int | None = None
    error_frames: int = 0
    counts: Counter[str] = field(default_factory=Counter)
    reported_at: float | None = None  # time of the last /can/bus_state message

    def note(self, error: CanError, time: float) -> bool:
        """Take one error frame in; True when a /can/bus_state message is due."""
        self.error_frames += 1
        self.counts.update(count_key(name) for name in error.classes)
        before = (self.state, self.tx_errors, self.rx_errors)
        state = next_state(self.state, error)
        if state != self.state or self.since is None:
            self.state, self.since = state, time
        if error.tx_errors is not None and error.rx_errors is not None:
            self.tx_errors, self.rx_errors = error.tx_errors, error.rx_errors
        due = (
            before != (self.state, self.tx_errors, self.rx_errors)
            or self.reported_at is None
            or not 0 <= time - self.reported_at < REPORT_INTERVAL_S
        )
        if due:
            self.reported_at = time
        return due

    def message(self) -> dict[str, Any]:
        """The fields of a /can/bus_state event (counters left out until reported)."""
        out = {
            "state": self.state,
            "level": LEVELS[self.state],
            "since": self.since,
            "tx_errors": self.tx_errors,
            "rx_errors": self.rx_errors,
            "error_frames": self.error_frames,
            "counts": dict(sorted(self.counts.items())),
        }
        return {key: value for key, value in out.items() if value is not None}
