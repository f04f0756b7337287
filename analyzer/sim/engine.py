"""The simulated gimbal without IO: decoded commands in, timed CAN frames (feedback, UAV) out."""

from __future__ import annotations

import heapq
from collections import Counter
from dataclasses import dataclass, field
from typing import Any

from analyzer.protocol.feedback import encode_attitude, encode_ranging
from analyzer.protocol.fields import CODE_SUFFIX
from analyzer.protocol.ids import ALTITUDE_ID, FEEDBACK_ID, GPS_ID, UAV_ATTITUDE_ID
from analyzer.protocol.types import (
    TOPIC_COMMAND,
    TOPIC_UAV_ALTITUDE,
    TOPIC_UAV_ATTITUDE,
    TOPIC_UAV_GPS,
    Event,
)
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.faults import FaultConfig, FaultInjector
from analyzer.sim.model import GimbalModel
from analyzer.sim.uav import FlightPath, UavPlayer

FEEDBACK_PERIOD = 0.5  # chapter 2.2: one full feedback message every 500 ms
RANGING_PERIOD = 2.0  # a ranging message takes the place of an attitude one this often

# Fields of a command event that say nothing a reader needs in a one-line summary.
_QUIET_FIELDS = frozenset({"s_id", "cmd", "name", "raw", "component", "transport", "direction"})


@dataclass(frozen=True)
class SimConfig:
    """What the simulated gimbal sends besides attitude feedback, and which faults it injects."""

    gimbal_type: int = 1
    feedback_period: float = FEEDBACK_PERIOD
    ranging: bool = False
    ranging_period: float = RANGING_PERIOD
    uav: bool = False
    faults: FaultConfig = field(default_factory=FaultConfig)
    behaviour: Behaviour = field(default_factory=Behaviour)
    heading_deg: float | None = None  # the aircraft's heading (psi = heading + motor yaw)
    attitude: tuple[float, float] = (0.0, 0.0)  # pitch, yaw motor where it starts (deg)


class SimulatedGimbal:
    """Gimbal model + feedback schedule + fault injection (+ the UAV when asked).

    ``handle(event, now)`` takes decoded events (commands, and UAV status when the UAV is
    not played here); ``poll(now)`` returns the (can_id, data) frames due by ``now`` in
    sending order; ``next_time()`` says when the next frame is due.
    """

    def __init__(self, start: float, config: SimConfig | None = None) -> None:
        self.config = config or SimConfig()
        self.start = start
        self.model = GimbalModel(
            start, gimbal_type=self.config.gimbal_type, behaviour=self.config.behaviour
        )
        self.model.point_at(*self.config.attitude)
        self.faults = FaultInjector(self.config.faults)
        heading = self.config.heading_deg
        if heading is not None:
            self.model.uav.heading_deg = heading
        self.uav = UavPlayer(start, FlightPath(heading_deg=heading)) if self.config.uav else None
        self.sent: Counter[str] = Counter()
        self._queue: list[tuple[float, int, int, bytes]] = []
        self._seq = 0
        self._feedback_clear = start  # segments leave in order: none before this time
        self._next_attitude = start
        self._next_ranging = start + self.config.feedback_period  # the second slot
        self._late: list[tuple[float, int, dict[str, Any]]] = []  # commands acted on later

    # -- input -----------------------------------------------------------------------------

    def handle(self, event: Event, now: float) -> bool:
        """Act on one decoded event; True when it was a command the gimbal acted on."""
        if event.topic == TOPIC_COMMAND:
            lag = self.config.behaviour.lag_s
            if lag:
                name = str(event.fields.get("name"))
                heapq.heappush(self._late, (now + lag, self._seq, event.fields))
                self._seq += 1
                return name not in self.config.behaviour.ignore
            return self.model.apply(event.fields, now)
        if self.uav is None:
            for attribute, name in _UAV_FIELDS.get(event.topic, ()):
                value = event.fields.get(name)
                if isinstance(value, (int, float)):
                    setattr(self.model.uav, attribute, float(value))
        return False

    # -- output ----------------------------------------------------------------------------

    def next_time(self) -> float:
        times = [self._next_attitude]
        if self.uav is not None:
            times.append(self.uav.next_time())
        if self._queue:
            times.append(self._queue[0][0])
        if self._late:
            times.append(self._late[0][0])
        return min(times)

    def poll(self, now: float) -> list[tuple[int, bytes]]:
        model = self.model
        while self._late and self._late[0][0] <= now:
            when, _, fields = heapq.heappop(self._late)
            model.apply(fields, when)
        if self.uav is not None:
            model.uav = self.uav.pose(now)
            for can_id, data in self.uav.due(now):
                self._push(now, can_id, data)
                self.sent[_UAV_NAMES.get(can_id, "text_frame")] += 1
        model.step(now)
        period = self.config.feedback_period
        stopped = self.faults.feedback_stopped(now - self.start)
        if now >= self._next_attitude:  # one feedback message per slot: attitude or ranging
            self._next_attitude = max(self._next_attitude + period, now)
            ranging = self.config.ranging and now >= self._next_ranging
            if ranging:
                self._next_ranging = max(self._next_ranging + self.config.ranging_period, now)
            if stopped:
                self.sent["attitude_suppressed"] += 1
            elif ranging:
                self._feedback(now, encode_ranging(**model.ranging()))
                self.sent["ranging"] += 1
            else:
                self._feedback(now, encode_attitude(**model.attitude()))
                self.sent["attitude"] += 1
        out: list[tuple[int, bytes]] = []
        while self._queue and self._queue[0][0] <= now:
            _, _, can_id, data = heapq.heappop(self._queue)
            out.append((can_id, data))
        return out

    def _feedback(self, now: float, message: bytes) -> None:
        for delay, segment in self.faults.segments(message):
            when = max(now + delay, self._feedback_clear)
            self._feedback_clear = when
            self._push(when, FEEDBACK_ID, segment)

    def _push(self, when: float, can_id: int, data: bytes) -> None:
        heapq.heappush(self._queue, (when, self._seq, can_id, data))
        self._seq += 1

    # -- reporting -------------------------------------------------------------------------

    def state_line(self) -> str:
        m = self.model
        return (
            f"pitch {m.pitch_deg:7.2f}  yaw {m.yaw_deg:6.2f}  motor yaw {m.motor_yaw_deg:7.2f}  "
            f"zoom {m.zoom:4.1f}x  tracking {'on' if m.tracking else 'off'}  "
            f"recording {'on' if m.recording else 'off'}"
        )

    def counts_line(self) -> str:
        parts = [f"{n} {k}" for k, n in sorted(self.sent.items())]
        faults = [f"{n} {k}" for k, n in sorted(self.faults.counts.items())]
        text = "sent " + (", ".join(parts) or "nothing")
        if faults:
            text += "; faults: " + ", ".join(faults)
        return text


# topic -> (UavPose attribute, event field) pairs: the aircraft the gimbal hangs under.
_UAV_FIELDS: dict[str, tuple[tuple[str, str], ...]] = {
    TOPIC_UAV_GPS: (("latitude_deg", "latitude_deg"), ("longitude_deg", "longitude_deg")),
    TOPIC_UAV_ALTITUDE: (("altitude_m", "altitude_m"),),
    TOPIC_UAV_ATTITUDE: (("heading_deg", "yaw_deg"),),
}
_UAV_NAMES = {GPS_ID: "gps", ALTITUDE_ID: "altitude", UAV_ATTITUDE_ID: "uav_attitude"}


def format_fields(fields: dict[str, Any], skip: frozenset[str] = frozenset()) -> str:
    """``key=value`` pairs on one line, floats to 10 significant digits, without trailing zeros."""
    return " ".join(
        f"{key}={value:.10g}" if isinstance(value, float) else f"{key}={value}"
        for key, value in fields.items()
        if key not in skip
    )


def describe_command(fields: dict[str, Any]) -> str:
    """A decoded command as one short line: ``gimbal_control pan_speed_dps=-5 ...``."""
    parts = [str(fields.get("name", "?"))]
    if fields.get("component") == "dual_sensor":
        parts.append("(dual_sensor)")
    # Labels are shown, so their ``*_code`` numbers are left out.
    shown = {k: v for k, v in fields.items() if not k.endswith(CODE_SUFFIX)}
    text = format_fields(shown, _QUIET_FIELDS)
    return " ".join([*parts, text] if text else parts)
