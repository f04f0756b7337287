"""What the report shows, folded event by event into bounded summaries; no IO.

Nothing here grows with the flight: plot series are :class:`Decimator` buckets, findings
are counted per command and check with a few examples kept, tables keep their first rows.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field
from typing import Any

from analyzer.analysis.streams import STREAM_GAP_S
from analyzer.analysis.verdict_counts import VerdictCounts
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
    TOPIC_UAV_TEXT,
    Event,
)
from analyzer.report.decimate import ATTITUDE_BUCKETS, Decimator, PerSecond, Row
from analyzer.report.finding_groups import FindingGroups

EARTH_M_PER_DEG = 111_320.0
MAX_ROWS = 2000  # rows of the diagnostics table
MAX_TEXTS = 500  # rows of the UAV status texts table
MAX_MARKS = 1500  # command marks kept (buckets of the whole flight)
MAX_TARGETS = 1500  # target crosses kept per verdict
STOP_AFTER_S = 0.3  # a gimbal_control speed counts as commanded this long after it was sent
MAX_RATE_GAP_S = 2.0  # attitude messages further apart give no measured rate


def _number(fields: dict[str, Any], name: str) -> float | None:
    value = fields.get(name)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    if not math.isfinite(value):
        return None
    return float(value)


def _stop_rows(last: tuple[float, float, float]) -> list[Row]:
    """A commanded speed holds until STOP_AFTER_S after its command, then falls to 0."""
    t, pan, tilt = last
    return [(t + STOP_AFTER_S, pan, tilt), (t + STOP_AFTER_S + 1e-3, 0.0, 0.0)]


@dataclass
class ReportData:
    """Series and tables of the report: ``add(event)`` for every event, findings of the
    response analysis included (or ``add_finding(fields)`` for those)."""

    source: str = ""
    format_name: str = ""
    first: float | None = None
    last: float | None = None
    topics: Counter[str] = field(default_factory=Counter)
    commands: Counter[str] = field(default_factory=Counter)
    diagnostic_kinds: Counter[str] = field(default_factory=Counter)
    # (t, pitch, yaw, motor yaw)
    attitude: Decimator = field(default_factory=lambda: Decimator((1, 2, 3), ATTITUDE_BUCKETS))
    # (t, command event): each command its mark; gimbal_control one per burst of the same
    # speeds, as the response analysis judges them
    marks: Decimator = field(default_factory=lambda: Decimator((), MAX_MARKS))
    commanded: Decimator = field(default_factory=lambda: Decimator((1, 2)))  # (t, pan, tilt)
    # (t, pan, tilt)
    measured: Decimator = field(default_factory=lambda: Decimator((1, 2), ATTITUDE_BUCKETS))
    altitude: Decimator = field(default_factory=lambda: Decimator((1,)))
    track: Decimator = field(default_factory=lambda: Decimator((1, 2)))  # (t, east m, north m)
    feedback: PerSecond = field(default_factory=lambda: PerSecond(zeros=True))
    errors: PerSecond = field(default_factory=lambda: PerSecond(zeros=False))
    # (t, target, verdict, text, axis) per verdict and axis
    targets: dict[tuple[str, str], Decimator] = field(default_factory=dict)
    diagnostics: list[tuple[float, str, str]] = field(default_factory=list)
    texts: list[tuple[float, str]] = field(default_factory=list)  # UAV status texts
    text_count: int = 0
    findings: FindingGroups = field(default_factory=FindingGroups)
    counts: VerdictCounts = field(default_factory=VerdictCounts)  # as analyze counts them
    notes: list[str] = field(default_factory=list)
    bus: BusFigures = field(default_factory=BusFigures)  # what the CAN error frames say
    frames: int = 0  # CAN frames read, error frames included (for the bus hints)
    untimed: bool = False  # set when the input has no clock (responses not judged)
    _last_attitude: tuple[float, float, float] | None = None  # (t, pitch, motor yaw)
    _last_speed: tuple[float, float, float] | None = None  # (t, pan, tilt)
    _gps_origin: tuple[float, float] | None = None

    def add(self, event: Event) -> None:
        t, topic, fields = event.time, event.topic, event.fields
        if topic == TOPIC_ANALYSIS_RESPONSE:
            self.add_finding(event.to_dict())
            return
        self.topics[topic] += 1
        if self.first is None or t < self.first:
            self.first = t
        if self.last is None or t > self.last:
            self.last = t
        if topic in (TOPIC_GIMBAL_ATTITUDE, TOPIC_GIMBAL_RANGING):
            self.feedback.add(t)
        if topic == TOPIC_GIMBAL_ATTITUDE:
            self._attitude(t, fields)
        elif topic == TOPIC_COMMAND:
            self._command(event)
        elif topic == TOPIC_UAV_ALTITUDE:
            altitude = _number(fields, "altitude_m")
            if altitude is not None:
                self.altitude.add((t, altitude))
        elif topic == TOPIC_UAV_GPS:
            self._gps(t, fields)
        elif topic == TOPIC_UAV_TEXT:
            self.text_count += 1
            if len(self.texts) < MAX_TEXTS:
                self.texts.append((t, str(fields.get("text", ""))))
        elif topic == TOPIC_DIAGNOSTICS:
            kind = str(fields.get("kind", "unknown"))
            self.diagnostic_kinds[kind] += 1
            self.errors.add(t)
            if kind == BUS_ERROR:
                self.bus.add_events((event,))
            if len(self.diagnostics) < MAX_ROWS:
                self.diagnostics.append((t, kind, str(fields.get("detail", ""))))

    def _attitude(self, t: float, fields: dict[str, Any]) -> None:
        pitch, yaw = _number(fields, "pitch_deg"), _number(fields, "yaw_deg")
        motor = _number(fields, "motor_yaw_deg")
        if pitch is None or yaw is None or motor is None:
            return
        self.attitude.add((t, pitch, yaw, motor))
        last = self._last_attitude
        if last is not None:
            dt = t - last[0]
            if 0 < dt <= MAX_RATE_GAP_S:
                self.measured.add(
                    ((last[0] + t) / 2, (motor - last[2]) / dt, (pitch - last[1]) / dt)
                )
        self._last_attitude = (t, pitch, motor)

    def _command(self, event: Event) -> None:
        t, fields = event.time, event.fields
        name = str(fields.get("name", "unknown"))
        self.commands[name] += 1
        if name != "gimbal_control":
            self.marks.add((t, event))
            return
        pan = _number(fields, "pan_speed_dps") or 0.0
        tilt = _number(fields, "tilt_speed_dps") or 0.0
        last = self._last_speed
        if last is not None and t - last[0] > STOP_AFTER_S:
            self._speeds_stop(last)
        moving = pan != 0 or tilt != 0
        if moving and (
            last is None or t - last[0] > STREAM_GAP_S or (last[1] == 0 and last[2] == 0)
        ):
            self.marks.add((t, event))  # the stick leaves its centre: a movement starts
        self.commanded.add((t, pan, tilt))
        self._last_speed = (t, pan, tilt)

    def _speeds_stop(self, last: tuple[float, float, float]) -> None:
        """The commanded speed holds until STOP_AFTER_S after the last command, then 0."""
        for row in _stop_rows(last):
            self.commanded.add(row)

    def _gps(self, t: float, fields: dict[str, Any]) -> None:
        lat, lon = _number(fields, "latitude_deg"), _number(fields, "longitude_deg")
        if lat is None or lon is None or (lat, lon) == (0.0, 0.0):
            return
        if self._gps_origin is None:
            self._gps_origin = (lat, lon)
        lat0, lon0 = self._gps_origin
        east = (lon - lon0) * EARTH_M_PER_DEG * math.cos(math.radians(lat0))
        self.track.add((t, east, (lat - lat0) * EARTH_M_PER_DEG))

    def add_finding(self, finding: dict[str, Any]) -> None:
        """One finding of the response analysis (an /analysis/response event's dict)."""
        self.findings.add(finding)
        self.counts.add(finding)
        target = _number(finding, "target_deg")
        if target is None:
            return
        verdict = str(finding.get("verdict"))
        what = f"{finding.get('command')} {target:g}: {finding.get('detail', '')}"
        for axis in str(finding.get("axis", "")).split("+"):
            series = self.targets.get((verdict, axis))
            if series is None:
                series = self.targets[verdict, axis] = Decimator((1,), MAX_TARGETS)
            series.add((float(finding["time"]), target, verdict, what, axis))

    def drop_findings(self) -> None:
        """Forget every finding (an input without a clock cannot time a response)."""
        self.findings.clear()
        self.counts.clear()
        self.targets.clear()

    # -- what the page shows -------------------------------------------------------------

    def commanded_rows(self) -> list[Row]:
        """The commanded speeds, back to 0 after the last command of the input too."""
        rows = self.commanded.rows()
        if self._last_speed is not None:
            rows += _stop_rows(self._last_speed)
        return rows

    def feedback_per_second(self) -> list[Row]:
        return self.feedback.rows(self.last)

    def errors_per_second(self) -> list[Row]:
        return self.errors.rows()

    def target_rows(self) -> list[Row]:
        return [row for series in self.targets.values() for row in series.rows()]

    def verdicts(self) -> Counter[str]:
        return self.findings.verdicts
