"""What the report shows, folded from decoded events and findings; no IO."""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field
from typing import Any

from analyzer.bus_figures import BusFigures
from analyzer.protocol.types import (
    BUS_ERROR,
    TOPIC_ANALYSIS_RESPONSE,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_GIMBAL_RANGING,
    TOPIC_UAV_ALTITUDE,
    TOPIC_UAV_GPS,
    Event,
)

EARTH_M_PER_DEG = 111_320.0
MAX_POINTS = 4000  # per plotted series; longer ones are thinned evenly
MAX_ROWS = 2000  # rows of the diagnostics table
STOP_AFTER_S = 0.3  # a gimbal_control speed counts as commanded this long after it was sent


def thin(points: list[Any], limit: int = MAX_POINTS) -> list[Any]:
    """Every n-th point so that at most ``limit`` remain (the last one always kept)."""
    if len(points) <= limit:
        return points
    step = math.ceil(len(points) / limit)
    kept = points[::step]
    if kept[-1] is not points[-1]:
        kept.append(points[-1])
    return kept


def _number(fields: dict[str, Any], name: str) -> float | None:
    value = fields.get(name)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value)


@dataclass
class ReportData:
    """Series and tables of the report; ``add(event)`` for every event and finding."""

    source: str = ""
    format_name: str = ""
    first: float | None = None
    last: float | None = None
    topics: Counter[str] = field(default_factory=Counter)
    commands: Counter[str] = field(default_factory=Counter)
    diagnostic_kinds: Counter[str] = field(default_factory=Counter)
    attitude: list[tuple[float, float, float, float]] = field(default_factory=list)
    command_marks: list[tuple[float, str]] = field(default_factory=list)
    speeds: list[tuple[float, float, float]] = field(default_factory=list)  # gimbal_control
    altitude: list[tuple[float, float]] = field(default_factory=list)
    gps: list[tuple[float, float, float]] = field(default_factory=list)
    diagnostics: list[tuple[float, str, str]] = field(default_factory=list)
    feedback_times: list[float] = field(default_factory=list)  # attitude and ranging
    findings: list[dict[str, Any]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    pictures: list[Any] = field(default_factory=list)  # camera thumbnails (report.camera)
    bus: BusFigures = field(default_factory=BusFigures)  # what the CAN error frames say
    frames: int = 0  # CAN frames read, error frames included (for the bus hints)

    def add(self, event: Event) -> None:
        t, topic, fields = event.time, event.topic, event.fields
        if topic == TOPIC_ANALYSIS_RESPONSE:
            self.findings.append(event.to_dict())
            return
        self.topics[topic] += 1
        if self.first is None or t < self.first:
            self.first = t
        if self.last is None or t > self.last:
            self.last = t
        if topic in (TOPIC_GIMBAL_ATTITUDE, TOPIC_GIMBAL_RANGING):
            self.feedback_times.append(t)
        if topic == TOPIC_GIMBAL_ATTITUDE:
            pitch, yaw = _number(fields, "pitch_deg"), _number(fields, "yaw_deg")
            motor = _number(fields, "motor_yaw_deg")
            if pitch is not None and yaw is not None and motor is not None:
                self.attitude.append((t, pitch, yaw, motor))
        elif topic == TOPIC_COMMAND:
            name = str(fields.get("name", "unknown"))
            self.commands[name] += 1
            if name == "gimbal_control":
                pan = _number(fields, "pan_speed_dps") or 0.0
                tilt = _number(fields, "tilt_speed_dps") or 0.0
                self.speeds.append((t, pan, tilt))
            if not self.command_marks or self.command_marks[-1][1] != name:
                self.command_marks.append((t, name))  # a repeated command marks once
        elif topic == TOPIC_UAV_ALTITUDE:
            altitude = _number(fields, "altitude_m")
            if altitude is not None:
                self.altitude.append((t, altitude))
        elif topic == TOPIC_UAV_GPS:
            lat, lon = _number(fields, "latitude_deg"), _number(fields, "longitude_deg")
            if lat is not None and lon is not None and (lat, lon) != (0.0, 0.0):
                self.gps.append((t, lat, lon))
        elif topic == TOPIC_DIAGNOSTICS:
            kind = str(fields.get("kind", "unknown"))
            self.diagnostic_kinds[kind] += 1
            if kind == BUS_ERROR:
                self.bus.add_events((event,))
            if len(self.diagnostics) < MAX_ROWS:
                self.diagnostics.append((t, kind, str(fields.get("detail", ""))))

    # -- derived series ------------------------------------------------------------------

    def measured_rates(self) -> list[tuple[float, float, float]]:
        """(mid time, pan deg/s, tilt deg/s) between consecutive attitude messages."""
        out = []
        for (t0, p0, _, m0), (t1, p1, _, m1) in zip(self.attitude, self.attitude[1:], strict=False):
            dt = t1 - t0
            if 0 < dt <= 2.0:
                out.append(((t0 + t1) / 2, (m1 - m0) / dt, (p1 - p0) / dt))
        return out

    def commanded_rates(self) -> list[tuple[float, float, float]]:
        """A step series of the commanded speeds, back to 0 when the commands stop."""
        out: list[tuple[float, float, float]] = []
        for i, (t, pan, tilt) in enumerate(self.speeds):
            nxt = self.speeds[i + 1][0] if i + 1 < len(self.speeds) else None
            out.append((t, pan, tilt))
            if nxt is None or nxt - t > STOP_AFTER_S:
                out.append((t + STOP_AFTER_S, pan, tilt))
                out.append((t + STOP_AFTER_S, 0.0, 0.0))
        return out

    def track_m(self) -> list[tuple[float, float]]:
        """(east, north) metres from the first GPS fix (flat earth, fine for one flight)."""
        if not self.gps:
            return []
        _, lat0, lon0 = self.gps[0]
        scale = EARTH_M_PER_DEG * math.cos(math.radians(lat0))
        return [((lon - lon0) * scale, (lat - lat0) * EARTH_M_PER_DEG) for _, lat, lon in self.gps]

    def feedback_per_second(self) -> list[tuple[float, int]]:
        """(second, feedback messages in it) for every second from the first to the last."""
        if self.first is None or self.last is None or not self.feedback_times:
            return []
        counts: Counter[int] = Counter(math.floor(t) for t in self.feedback_times)
        start, end = math.floor(self.first), math.floor(self.last)
        first = self.first
        return [(max(s, first), counts.get(s, 0)) for s in range(start, end + 1)]

    def errors_per_second(self) -> list[tuple[float, int]]:
        counts: Counter[int] = Counter(math.floor(t) for t, _, _ in self.diagnostics)
        return sorted(counts.items())

    def verdicts(self) -> Counter[str]:
        return Counter(str(f.get("verdict")) for f in self.findings)
