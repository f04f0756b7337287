"""Judging only when a judgement is due gives the findings of looking at every event.

The response analysis skips its pending judgements between feedback messages until the
earliest of them can be due (a deadline, a stream's pause, a movement's window, a stop
check), and the feedback health skips its minute windows until the next can close. A
stick streamed at 20 Hz makes that the most frequent case; here an analyzer that looks at
everything at every event gives, event for event, the same findings on random traffic:
sticks of two components, zeros and pauses, targets, tracking, feedback with outages
and damage, clocks that step back.
"""

from __future__ import annotations

import math
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from analyzer.analysis.health import FeedbackHealth
from analyzer.analysis.response import ResponseAnalyzer
from analyzer.protocol.types import (
    CRC_MISMATCH,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_UAV_ATTITUDE,
    Event,
)
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.engine import SimConfig
from analyzer.sim.faults import FaultConfig
from analyzer.sim.ground import DEMO_SCRIPT, pilot_script
from analyzer.sim.offline import run_offline


class EveryEventHealth(FeedbackHealth):
    """Feedback health that works out the minute window of every event."""

    def tick(self, t: float) -> list[Any]:
        self._next_window = -math.inf
        return super().tick(t)


class EveryEventAnalyzer(ResponseAnalyzer):
    """The response analysis looking at every pending judgement at every event."""

    def __init__(self) -> None:
        super().__init__()
        self.health = EveryEventHealth()

    def _next_due(self) -> float:
        return -math.inf


def findings(analyzer: ResponseAnalyzer, events: list[Event]) -> list[tuple[int, dict[str, Any]]]:
    """Each finding with the number of the event that gave it (the end: len(events))."""
    out = [(n, e.to_dict()) for n, event in enumerate(events) for e in analyzer.feed(event)]
    return out + [(len(events), e.to_dict()) for e in analyzer.close()]


def assert_same(events: list[Event]) -> int:
    """The same findings at the same events; how many."""
    due = findings(ResponseAnalyzer(), events)
    assert due == findings(EveryEventAnalyzer(), events)
    return len(due)


def command(t: float, name: str, **fields: Any) -> Event:
    return Event(TOPIC_COMMAND, t, "can0", {"name": name, **fields})


def attitude(t: float, pitch: float, yaw: float, tracking: bool) -> Event:
    fields = {"pitch_deg": pitch, "yaw_deg": yaw, "motor_yaw_deg": yaw, "tracking": tracking}
    return Event(TOPIC_GIMBAL_ATTITUDE, t, "can0", fields)


SPEED = st.sampled_from([0.0, 5.0, -12.5, 30.0, 0.25])
ANGLE = st.floats(-90, 30, allow_nan=False)


@st.composite
def phase(draw: st.DrawFn) -> dict[str, Any]:
    """A stretch of traffic: perhaps a command at its start, then a stream of stick
    commands (or zeros, or only the flight controller's attitude) at a cadence, with the
    gimbal's feedback every 0.5 s or none (an outage), turning at its own rate."""
    return {
        "command": draw(st.sampled_from([None, "pitch", "yaw", "tracking", "tracking_stop"])),
        "angle": draw(ANGLE),
        "stream": draw(st.sampled_from(["stick", "stick", "zeros", "uav", "nothing"])),
        "component": draw(st.sampled_from(["gimbal", "dual_sensor"])),
        "speeds": (draw(SPEED), draw(SPEED)),
        "seconds": draw(st.floats(0.05, 12.0)),
        "cadence": draw(st.sampled_from([0.05, 0.05, 0.1, 0.3])),
        "feedback": draw(st.sampled_from([True, True, False])),
        "damaged": draw(st.booleans()),
        "turning": (draw(st.floats(-20, 20)), draw(st.floats(-20, 20))),
        "tracking": draw(st.booleans()),
        "then": draw(st.sampled_from([0.0, 0.0, 0.7, 1.5, 61.0, -0.4])),  # the gap after it
    }


def traffic(phases: list[dict[str, Any]]) -> list[Event]:
    """The events of ``phases``, one after the other."""
    t = 1_715_680_800.0
    pitch, yaw = 0.0, 0.0
    events: list[Event] = []
    for p in phases:
        if p["command"] in ("pitch", "yaw"):
            axis = p["command"]
            events.append(command(t, "specified_angle", axis=axis, **{f"{axis}_deg": p["angle"]}))
        elif p["command"] is not None:
            events.append(command(t, p["command"]))
        end, next_feedback = t + p["seconds"], t
        pan, tilt = p["speeds"] if p["stream"] == "stick" else (0.0, 0.0)
        while t < end:
            if p["feedback"] and t >= next_feedback:
                pitch = max(-90.0, min(30.0, pitch + p["turning"][1] * 0.5))
                yaw = (yaw + p["turning"][0] * 0.5 + 180.0) % 360.0 - 180.0
                events.append(attitude(t, pitch, yaw, p["tracking"]))
                if p["damaged"]:
                    events.append(Event(TOPIC_DIAGNOSTICS, t, "can0", {"kind": CRC_MISMATCH}))
                next_feedback = t + 0.5
            if p["stream"] in ("stick", "zeros"):
                fields = {"pan_speed_dps": pan, "tilt_speed_dps": tilt, "component": p["component"]}
                events.append(command(t, "gimbal_control", **fields))
            elif p["stream"] == "uav":
                events.append(Event(TOPIC_UAV_ATTITUDE, t, "can0", {"roll_deg": 0.0}))
            t += p["cadence"]
        t += p["then"]
    return events


@settings(max_examples=150, deadline=None)
@given(st.lists(phase(), min_size=1, max_size=12))
def test_random_traffic_gets_the_same_findings(phases: list[dict[str, Any]]) -> None:
    assert_same(traffic(phases))


def test_a_pilots_minute_with_link_faults_gets_the_same_findings() -> None:
    faults = FaultConfig(drop=0.05, corrupt=0.02, duplicate=0.02, delay=0.02, seed=5)
    late = Behaviour(lag_s=0.4, speed=0.7, drift_s=0.5)
    for config in (SimConfig(uav=True, faults=faults), SimConfig(behaviour=late)):
        _, events = run_offline(pilot_script(), 60.0, config, start=1_715_680_800.0)
        assert assert_same(events) >= 5  # the stick's movements, their stops, the health


def test_the_demo_script_gets_the_same_findings() -> None:
    _, events = run_offline(DEMO_SCRIPT, 14.0, SimConfig(ranging=True, uav=True))
    assert assert_same(events) >= 5  # the script's commands are judged
