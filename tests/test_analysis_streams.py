"""Streams of gimbal_control as ground stations send them: a pilot's stick (speeds changing
in every command, 20 Hz), re-sent targets and a tracker's box updates are each judged once.

The document (chapter 2.1, 0x04): "If you keep sending this command, the gimbal will keep
rotating, 50ms at a time is recommended; if you stop sending it, it will stop rotating."
A movement of the stick is judged by its commanded motion (the speeds integrated) against
the motion the feedback shows, every 0.5 s.
"""

from __future__ import annotations

import random
from collections import Counter
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from analyzer.analysis.motion_fit import CommandedMotion, StickCommand
from analyzer.analysis.streams import HOLD_S
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.ground import Step
from analyzer.sim.pilot import Stick
from tests.test_analysis_response import session

# (start s, length s, peak pan deg/s, peak tilt deg/s): four movements in a minute.
MOVES = (
    (2.0, 3.0, 20.0, 0.0),
    (15.0, 2.0, 0.0, -15.0),
    (30.0, 4.0, -12.0, 8.0),
    (45.0, 2.5, 30.0, 10.0),
)
MINUTE = 60.0


def pilot(
    *, centred: str = "zeros", component: str = "gimbal", released: bool = False
) -> tuple[Step, ...]:
    """A pilot's minute: four stick movements; while the stick is centred the ground
    station sends zeros every 50 ms (``zeros``) or nothing (``pause``)."""
    params = {"component": component}
    steps = []
    for n, (at, length, pan, tilt) in enumerate(MOVES):
        centred_s = 8.0 if centred == "zeros" else 0.0
        stick = Stick(pan, tilt, centred_s=centred_s, seed=n, released=released)
        steps.append(Step(at, "gimbal_control", params, until=at + length, stick=stick))
    return tuple(steps)


def checks(
    found: list[dict[str, Any]], command: str = "gimbal_control"
) -> Counter[tuple[str, str]]:
    return Counter((f["check"], f["verdict"]) for f in found if f["command"] == command)


def rates(found: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [f for f in found if f["command"] == "gimbal_control" and f["check"] == "rate"]


# -- a pilot's stick against gimbals that obey and that do not -------------------------------


@pytest.mark.parametrize("centred", ["zeros", "pause"])
def test_a_gimbal_that_follows_the_stick(centred: str) -> None:
    found = session(pilot(centred=centred), MINUTE)
    assert checks(found) == {("rate", "obeyed"): 4, ("stop", "obeyed"): 4}
    first, second, third, fourth = rates(found)
    assert first["pan_ratio"] == pytest.approx(1, abs=0.05) and "tilt_ratio" not in first
    assert second["tilt_ratio"] == pytest.approx(1, abs=0.05) and "pan_ratio" not in second
    assert third["pan_ratio"] == pytest.approx(1, abs=0.05)
    assert third["tilt_ratio"] == pytest.approx(1, abs=0.05)
    assert fourth["command_count"] == pytest.approx(2.5 * 20, abs=3)
    for rate, (at, length, pan, _) in zip(rates(found), MOVES, strict=True):
        assert rate["time"] == pytest.approx(at, abs=0.2)
        assert rate["duration_s"] == pytest.approx(length, abs=0.3)
        assert rate["interval_mean_s"] == pytest.approx(0.05, abs=0.001)
        assert rate["lag_s"] == pytest.approx(0, abs=0.05)
        if pan:
            # the stick's profile: the peak is reached, the mean is less
            assert abs(rate["peak_pan_dps"]) == pytest.approx(abs(pan), rel=0.1)
            assert 0.5 < rate["commanded_pan_dps"] / pan < 1.0


def test_a_gimbal_that_lags_behind_the_stick() -> None:
    found = session(pilot(), MINUTE, behaviour=Behaviour(lag_s=0.4))
    assert checks(found)[("rate", "obeyed")] == 4
    for rate in rates(found):
        assert rate["lag_s"] == pytest.approx(0.4, abs=0.1)
        assert rate["rate_ratio"] == pytest.approx(1, abs=0.05)
        assert "followed about 0.4 s late" in rate["detail"]


def test_a_gimbal_that_turns_at_four_tenths_of_the_stick() -> None:
    found = session(pilot(), MINUTE, behaviour=Behaviour(speed=0.4))
    assert checks(found) == {("rate", "partial"): 4, ("stop", "obeyed"): 4}
    for rate in rates(found):
        assert rate["rate_ratio"] == pytest.approx(0.4, abs=0.03)
        assert "sluggish" in rate["detail"]


def test_a_frozen_gimbal() -> None:
    frozen = Behaviour(ignore=frozenset({"gimbal_control"}))
    found = session(pilot(), MINUTE, behaviour=frozen)
    assert checks(found) == {("rate", "not_obeyed"): 4, ("stop", "obeyed"): 4}
    assert all("hardly moved" in r["detail"] and "lag_s" not in r for r in rates(found))


def test_the_three_gimbals_get_three_verdicts() -> None:
    """What the issue was about: they used to get identical verdicts."""
    verdicts = {
        name: sorted({r["verdict"] for r in rates(session(pilot(), MINUTE, behaviour=b))})
        for name, b in (
            ("follows", Behaviour()),
            ("slow", Behaviour(speed=0.4)),
            ("frozen", Behaviour(ignore=frozenset({"gimbal_control"}))),
        )
    }
    assert verdicts == {"follows": ["obeyed"], "slow": ["partial"], "frozen": ["not_obeyed"]}


def test_a_gimbal_that_turns_the_wrong_way() -> None:
    """A pan sent to the dual-sensor gimbal that the simulator turns as commanded, judged
    against a gimbal mounted the other way round is no simulator option: a stream whose
    commanded motion is the negative of the feedback's is the same finding."""
    from analyzer.analysis.motion_fit import CommandedMotion, StickCommand, fit

    motion = CommandedMotion([StickCommand(0.05 * i, 20.0, 0.0) for i in range(40)], 0.3)
    feedback = [(0.5 * i, -20.0 * min(0.5 * i, 2.3)) for i in range(8)]
    found = fit(motion, {0: feedback})
    assert found is not None and found.axes[0].ratio == pytest.approx(-1, abs=0.05)


def test_a_gimbal_that_keeps_turning_after_the_stick_is_let_go() -> None:
    """The pilot lets go of the stick at full speed: the last commands still ask for it."""
    found = session(pilot(centred="pause", released=True), MINUTE, behaviour=Behaviour(drift_s=1.5))
    stops = [f for f in found if f["check"] == "stop"]
    assert len(stops) == 4 and {f["verdict"] for f in stops} == {"not_obeyed"}
    assert all("still moving" in f["detail"] for f in stops)


def test_a_movement_into_the_pitch_limit() -> None:
    stick = Stick(0.0, -60.0, centred_s=3.0)
    steps = (Step(1.0, "gimbal_control", {}, until=5.0, stick=stick),)
    found = session(steps, 10.0)
    limit = [f for f in found if f["check"] == "limit"]
    assert len(limit) == 1 and limit[0]["limit_deg"] == -110
    (rate,) = rates(found)
    assert rate["verdict"] == "obeyed" and "then at its limit -110.0" in rate["detail"]


def test_the_dual_sensor_gimbal_control_is_its_own_stream() -> None:
    found = session(pilot(component="dual_sensor"), MINUTE, behaviour=Behaviour(speed=0.4))
    assert {r["component"] for r in rates(found)} == {"dual_sensor"}
    assert checks(found)[("rate", "partial")] == 4
    both = (
        *pilot(),
        *(
            Step(s.at + 7, s.name, {"component": "dual_sensor"}, s.until and s.until + 7, s.stick)
            for s in pilot()
        ),
    )
    found = session(both, MINUTE + 8)
    assert Counter(r["component"] for r in rates(found)) == {"gimbal": 4, "dual_sensor": 4}


def test_the_speeds_changing_in_every_command_is_no_cadence_problem() -> None:
    found = session(pilot(), MINUTE)
    assert not [f for f in found if f["check"] == "repeat"]


def test_jitter_in_the_sending_times_changes_nothing() -> None:
    """A ground station on a busy computer sends every 50 ms +- 20 ms."""
    from analyzer.analysis.response import ResponseAnalyzer
    from analyzer.protocol.types import TOPIC_COMMAND, Event
    from analyzer.sim.offline import run_offline

    _, events = run_offline(pilot(), MINUTE)
    rng = random.Random(5)
    jittered = [
        Event(e.topic, e.time + rng.uniform(-0.02, 0.02), e.source, e.fields)
        if e.topic == TOPIC_COMMAND
        else e
        for e in events
    ]
    jittered.sort(key=lambda e: e.time)
    analyzer = ResponseAnalyzer()
    found = [f.to_dict() for e in jittered for f in analyzer.feed(e)]
    found += [f.to_dict() for f in analyzer.close()]
    assert checks(found)[("rate", "obeyed")] == 4
    assert not [f for f in found if f["check"] == "repeat"]


# -- cadence ------------------------------------------------------------------------------------


def test_a_stream_too_slow_to_keep_the_gimbal_moving_is_said_once() -> None:
    steps = tuple(
        Step(1.0 + 0.25 * i, "gimbal_control", {"pan_speed_dps": 10 + (i % 3)}) for i in range(30)
    )
    found = session(steps, 12.0)
    (repeat,) = [f for f in found if f["check"] == "repeat"]
    assert repeat["interval_mean_s"] == pytest.approx(0.25, abs=0.01)
    assert repeat["command_count"] == 30 and "recommends 50 ms" in repeat["detail"]


def test_a_pause_the_gimbal_stops_in_is_a_cadence_problem() -> None:
    fast = tuple(Step(1.0 + 0.05 * i, "gimbal_control", {"tilt_speed_dps": 10}) for i in range(20))
    later = tuple(Step(2.6 + 0.05 * i, "gimbal_control", {"tilt_speed_dps": 10}) for i in range(20))
    found = session(fast + later, 8.0)
    (repeat,) = [f for f in found if f["check"] == "repeat"]
    assert repeat["interval_max_s"] == pytest.approx(0.65, abs=0.01)
    assert len(rates(found)) == 1


# -- re-sent targets -----------------------------------------------------------------------------


def test_a_target_re_sent_until_it_is_reached_is_one_judgement() -> None:
    steps = tuple(Step(1.0 + 0.2 * i, "specified_angle", {"pitch_deg": -45}) for i in range(16))
    found = session(steps, 10.0, behaviour=Behaviour(speed=0.25))
    (target,) = [f for f in found if f["check"] == "target"]
    assert target["verdict"] == "obeyed" and target["command_count"] == 16
    assert target["resent_for_s"] == pytest.approx(3.0, abs=0.01)
    assert "sent 16 times over 3.0 s" in target["detail"]


def test_a_different_target_supersedes_the_one_pending() -> None:
    first = tuple(Step(1.0 + 0.2 * i, "specified_angle", {"pitch_deg": -45}) for i in range(5))
    second = tuple(Step(2.0 + 0.2 * i, "specified_angle", {"pitch_deg": -10}) for i in range(5))
    found = session(first + second, 10.0, behaviour=Behaviour(speed=0.25))
    old, new = [f for f in found if f["check"] == "target"]
    assert old["target_deg"] == -45 and old["command_count"] == 5
    assert old["verdict"] == "unknown" and "specified_angle came 1.0 s later" in old["detail"]
    assert new["target_deg"] == -10 and new["verdict"] == "obeyed"


def test_a_yaw_target_in_another_frame_is_no_re_send() -> None:
    steps = (
        Step(1.0, "specified_angle", {"yaw_deg": 40}),
        Step(1.2, "specified_angle", {"yaw_deg": 40, "coordinate_system": "airframe"}),
    )
    found = session(steps, 8.0)
    assert len([f for f in found if f["check"] == "target"]) == 2


# -- tracking sessions ---------------------------------------------------------------------------


def test_a_tracker_updating_its_box_at_10_hz_is_one_session() -> None:
    box = {"x": 4200, "y": 4000, "width": 480, "height": 320}
    updates = tuple(Step(1.0 + 0.1 * i, "tracking", box) for i in range(60))
    found = session((*updates, Step(7.5, "tracking_stop")), 12.0)
    start, stop = [f for f in found if f["check"] == "tracking"]
    assert start["command"] == "tracking" and start["verdict"] == "obeyed"
    assert stop["command"] == "tracking_stop" and stop["verdict"] == "obeyed"
    assert stop["command_count"] == 60 and stop["updates_hz"] == pytest.approx(10, abs=0.1)
    assert stop["duration_s"] == pytest.approx(6.5, abs=0.01)


def test_a_tracker_the_gimbal_ignores_is_one_not_obeyed() -> None:
    box = {"x": 4200, "y": 4000, "width": 480, "height": 320}
    updates = tuple(Step(1.0 + 0.1 * i, "tracking", box) for i in range(60))
    ignored = Behaviour(ignore=frozenset({"tracking"}))
    found = session((*updates, Step(7.5, "tracking_stop")), 12.0, behaviour=ignored)
    verdicts = [(f["command"], f["verdict"]) for f in found if f["check"] == "tracking"]
    assert verdicts == [("tracking", "not_obeyed"), ("tracking_stop", "unknown")]


def test_feedback_that_comes_late_or_not_at_all_does_not_bend_the_ratio() -> None:
    """Late segments date a message after the gimbal measured it (left out of the fit);
    lost messages leave fewer intervals (with fewer than three, no lag is claimed)."""
    from analyzer.sim.faults import FaultConfig

    faults = FaultConfig(delay=0.2, drop=0.1, seed=4)
    found = session(pilot(), MINUTE, faults=faults)
    for rate in rates(found):
        assert rate["verdict"] == "obeyed", rate
        assert rate["rate_ratio"] == pytest.approx(1, abs=0.1)
    short = (Step(1.0, "gimbal_control", {"pan_speed_dps": 25}, until=1.6),)
    (rate,) = rates(session(short, 7.0, faults=FaultConfig(stop_at=1.7, stop_for=3.0)))
    assert "lag_s" not in rate and rate["verdict"] == "obeyed"


def _corners_one_by_one(
    commands: list[StickCommand], hold: float
) -> tuple[list[float], list[float], list[float]]:
    """The commanded motion's corners as a running total makes them, command by command."""
    times: list[float] = []
    pans: list[float] = []
    tilts: list[float] = []
    pan = tilt = 0.0
    for n, this in enumerate(commands):
        until = this.time + hold
        if n + 1 < len(commands):
            until = min(until, commands[n + 1].time)
        times.append(this.time)
        pans.append(pan)
        tilts.append(tilt)
        span = max(0.0, until - this.time)
        pan += this.pan * span
        tilt += this.tilt * span
        times.append(max(until, this.time))
        pans.append(pan)
        tilts.append(tilt)
    return times, pans, tilts


@given(
    st.lists(
        st.tuples(
            st.sampled_from([0.0, 0.01, 0.05, 0.3, 0.5, -0.01]),
            st.floats(-100, 100),
            st.floats(-100, 100),
        ),
        max_size=40,
    ),
    st.floats(0, 2e9),
)
def test_the_commanded_motion_is_the_running_total_of_the_commands(
    steps: list[tuple[float, float, float]], start: float
) -> None:
    """Its corners are made for all commands at once: the same floats as a running total."""
    commands, t = [], start
    for step, pan, tilt in steps:
        t += step
        commands.append(StickCommand(t, pan, tilt))
    motion = CommandedMotion(commands, HOLD_S)
    times, pans, tilts = _corners_one_by_one(commands, HOLD_S)
    assert motion.times.tolist() == times
    assert [a.tolist() for a in motion._axes] == [pans, tilts]
