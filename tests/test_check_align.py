"""Each step of `check` first brings the gimbal to its start, from wherever it was left.

``analyzer.check.align.bring_to`` turns the gimbal to an attitude and waits until the
feedback shows it there, or says why not; the check's runner calls it before every
step, and a replay can call it with any link, observer and clock. These tests drive it
and the whole check on a simulated gimbal in virtual time (``analyzer.check.offline``),
where a 40 s check takes a tenth of a second; ``test_check_command`` runs the same over
TCP in real time.
"""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from analyzer.analysis.samples import MOTOR_YAW, PITCH, YAW
from analyzer.check.align import Arrival, Goals, bring_to
from analyzer.check.judge import Limits
from analyzer.check.offline import SimulatedBench
from analyzer.check.output import TablePrinter
from analyzer.check.steps import STEPS, Attitude, Options, select
from analyzer.protocol.check_fields import FAIL, PASS, SKIPPED
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.engine import SimConfig
from analyzer.sim.faults import FaultConfig

HOWTO = Path(__file__).resolve().parents[1] / "docs" / "howto" / "check.md"
# Attitudes a gimbal may be left in: its corners, straight down, looking back, level.
LEFT_AT = [(0.0, 0.0), (-45.0, 120.0), (-110.0, -170.0), (60.0, 170.0), (-90.0, -95.5), (30, -20)]


def settled_bench(config: SimConfig) -> SimulatedBench:
    """A bench whose gimbal has spoken for a second (two feedback messages)."""
    bench = SimulatedBench(config)
    bench.sleep(1.0)
    return bench


def arrive(bench: SimulatedBench, goals: Goals, timeout_s: float = 8.0) -> Arrival:
    return bring_to(
        bench, bench.observer, goals, tolerance_deg=1.0, timeout_s=timeout_s, clock=bench
    )


@pytest.mark.parametrize("left_at", LEFT_AT)
def test_it_brings_the_gimbal_to_an_attitude_and_waits_until_it_is_there(
    left_at: tuple[float, float],
) -> None:
    bench = settled_bench(SimConfig(attitude=left_at, heading_deg=30.0))
    arrival = arrive(bench, ((PITCH, -30.0), (MOTOR_YAW, 45.0)))
    assert arrival.reached and arrival.reason == ""
    assert arrival.sample is not None
    assert arrival.sample.pitch == pytest.approx(-30.0, abs=1.0)
    assert arrival.sample.motor_yaw == pytest.approx(45.0, abs=1.0)
    assert arrival.sent == (
        "specified_angle axis=pitch pitch_deg=-30",
        "specified_angle axis=yaw yaw_deg=45 coordinate_system=airframe",
    )
    # It waited for the feedback: the turn of the farther axis at the simulator's 60 deg/s.
    farthest = max(abs(left_at[0] + 30.0), abs(left_at[1] - 45.0))
    assert arrival.took_s >= farthest / 60.0
    # The model is there too (not only the feedback that was waited for).
    assert bench.gimbal.model.pitch_deg == pytest.approx(-30.0)


def test_a_yaw_from_north_and_an_attitude_it_is_already_at() -> None:
    bench = settled_bench(SimConfig(attitude=(-10.0, 20.0), heading_deg=30.0))
    arrival = arrive(bench, ((YAW, 350.0),))  # heading 30: the motor at -40
    assert arrival.reached and arrival.sample is not None
    assert arrival.sample.motor_yaw == pytest.approx(-40.0, abs=1.0)
    assert "coordinate_system=geodetic" in arrival.sent[0]
    again = arrive(bench, ((PITCH, -10.0), (MOTOR_YAW, -40.0)))
    assert again.reached and again.sent == () and again.took_s == 0.0  # nothing to send


@pytest.mark.parametrize(
    ("config", "goals", "words"),
    [
        (
            SimConfig(attitude=(-45.0, 120.0), behaviour=Behaviour(speed=0.0)),
            ((PITCH, 0.0), (MOTOR_YAW, 0.0)),
            "pitch at -45.0, 45.0 deg off (it did not move); yaw motor at 120.0, 120.0 deg off",
        ),
        (SimConfig(), ((MOTOR_YAW, 175.0),), "yaw motor 175.0 is beyond the yaw motor's range"),
        (SimConfig(), ((PITCH, -105.0),), "pitch -105.0 cannot be asked for"),
    ],
)
def test_when_it_cannot_get_there_it_says_why(config: SimConfig, goals: Goals, words: str) -> None:
    bench = settled_bench(config)
    began = bench.now
    arrival = arrive(bench, goals)
    assert not arrival.reached and words in arrival.reason, arrival.reason
    # A gimbal that stopped elsewhere is not waited for until the timeout.
    assert bench.now - began < 4.0


def test_a_gimbal_that_stops_short_is_asked_again_while_it_comes_nearer() -> None:
    """70 % of the way each time: 42, 55, 58, then within the tolerance of 60; at half
    the way it is still 3.8 deg off after the fourth time, and that is said."""
    near = arrive(settled_bench(SimConfig(behaviour=Behaviour(reach=0.7))), ((PITCH, -60.0),))
    assert near.reached and len(near.sent) == 4
    half = arrive(settled_bench(SimConfig(behaviour=Behaviour(reach=0.5))), ((PITCH, -60.0),))
    assert not half.reached and len(half.sent) == 4
    assert half.reason.endswith("pitch at -56.2, 3.8 deg off (moved 56.2 deg)")


def test_a_long_turn_goes_in_legs_each_within_the_time_allowed() -> None:
    """From the back stop on one side to 150 on the other: 320 deg, in three legs of
    at most 150 (what a gimbal at 30 deg/s turns in 5 s), so that the analysis, which
    judges each command within its 5 s, sees every leg reached."""
    bench = settled_bench(SimConfig(attitude=(0.0, -170.0)))
    arrival = bring_to(
        bench,
        bench.observer,
        ((MOTOR_YAW, 150.0),),
        tolerance_deg=1.0,
        timeout_s=15.0,
        clock=bench,
        max_turn_deg=150.0,
    )
    assert arrival.reached
    assert arrival.sent == tuple(
        f"specified_angle axis=yaw yaw_deg={angle} coordinate_system=airframe"
        for angle in ("296.7", "43.3", "150")  # -63.3 and 43.3 from the nose
    )
    targets = [e.fields for e in bench.finish() if e.fields.get("check") == "target"]
    assert [t["verdict"] for t in targets] == ["obeyed"] * 3


def test_without_feedback_it_says_so() -> None:
    silent = FaultConfig(stop_at=0.5, stop_for=60.0)
    bench = settled_bench(SimConfig(attitude=(-45.0, 120.0), faults=silent))
    arrival = arrive(bench, ((PITCH, 0.0),), timeout_s=3.0)
    assert not arrival.reached and not arrival.heard
    assert arrival.reason == "no attitude feedback came within 3.0 s of the commands"


@pytest.mark.parametrize("left_at", LEFT_AT)
def test_a_healthy_gimbal_passes_every_step_from_any_attitude(
    left_at: tuple[float, float],
) -> None:
    for steps in [STEPS, *((step,) for step in STEPS)]:  # the sequence, and each alone
        bench = SimulatedBench(SimConfig(attitude=left_at, heading_deg=200.0))
        results = bench.check(steps)
        assert [r.step for r in results] == [s.name for s in steps]
        for result in results:
            want = SKIPPED if result.step == "zoom" else PASS
            assert result.verdict == want, (left_at, result.step, result.detail)
            if "slew_dps" in result.figures:
                assert result.figures["slew_dps"] == pytest.approx(60.0, rel=0.05)


@pytest.mark.parametrize("step", ["pan_speed", "tilt_speed"])
def test_a_speed_step_held_past_the_whole_range_passes_a_healthy_gimbal(step: str) -> None:
    """20 deg/s for 20 s crosses the whole range: the step starts at the stop it turns
    away from and ends at the other one. Starting at a stop is no turn the wrong way."""
    bench = SimulatedBench(SimConfig(attitude=(-45.0, 120.0)))
    (result,) = bench.check(select(step), Options(speed_dps=20.0, speed_for_s=20.0))
    assert result.verdict == PASS, result.detail
    assert "the wrong way" not in result.detail and "then at its limit" in result.detail


def test_each_step_starts_from_the_same_attitude_wherever_the_gimbal_was() -> None:
    """The start is the step's own: its target and figures do not depend on where the
    gimbal was left (the move from pitch 45 to -90 is measured whatever came before)."""
    figures = []
    for left_at in LEFT_AT:
        (result,) = SimulatedBench(SimConfig(attitude=left_at)).check(select("pitch_angle"))
        figures.append((result.figures["target_deg"], round(result.figures["slew_dps"])))
    assert set(figures) == {(-90.0, 60)}


def test_a_step_whose_start_cannot_be_reached_fails_with_that_reason() -> None:
    frozen = SimConfig(attitude=(-45.0, 120.0), behaviour=Behaviour(speed=0.0))
    bench = SimulatedBench(frozen, Limits(min_slew_dps=30.0))
    results = bench.check(select("pitch_angle,tracking"))
    pitch, tracking = results
    assert pitch.verdict == FAIL
    assert pitch.detail == (
        "the gimbal could not be brought to the step's start (pitch 45.0): not at pitch 45.0 "
        "after 2.0 s: pitch at -45.0, 90.0 deg off (it did not move)"
    )
    assert tracking.verdict == PASS  # the tracking flag needs no start: it still works
    # The judged command never went: only the start's specified_angle did.
    commands = [e.fields for e in bench.finish() if e.topic == "/gimbal/command"]
    assert [c.get("pitch_deg") for c in commands if c["name"] == "specified_angle"] == [45.0]


def test_a_speed_step_turns_across_the_middle_of_the_range() -> None:
    """pan_speed starts left of the nose so that its turn ends as far right (a turn of
    100 deg/s for 3 s fits: -150 to 150); tilt_speed turns down across -25."""
    options = Options(speed_dps=100.0, speed_for_s=3.0)
    pan = select("pan_speed")[0].plan
    tilt = select("tilt_speed")[0].plan
    assert pan(Attitude(), options).start == ((MOTOR_YAW, -150.0),)
    assert tilt(Attitude(), Options()).start == ((PITCH, -5.0),)
    bench = SimulatedBench(SimConfig(attitude=(50.0, 160.0)))
    (result,) = bench.check(select("pan_speed"), options)
    assert result.verdict == PASS and result.figures["rate_dps"] == pytest.approx(100, rel=0.15)


def test_the_manual_shows_the_failure_the_check_prints() -> None:
    """docs/howto/check.md shows a frozen gimbal left at pitch -45 / yaw 120."""
    frozen = SimConfig(attitude=(-45.0, 120.0), behaviour=Behaviour(speed=0.0))
    (result,) = SimulatedBench(frozen).check(select("pitch_angle"))
    out = io.StringIO()
    TablePrinter(out)(result)
    printed = out.getvalue().splitlines()[1:]  # below the header
    shown = HOWTO.read_text(encoding="utf-8").splitlines()
    at = shown.index("    " + printed[0].rstrip())
    assert [line.removeprefix("    ") for line in shown[at : at + 2]] == printed
