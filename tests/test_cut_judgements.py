"""Judgements at the edges: a movement, target or tracking session cut by the end of the
input or by a gap in the feedback is ``unknown``, with the reason in words; no verdict
comes from fewer feedback intervals than the fit needs; a late gimbal's motion is
counted in the movement that caused it.

Each case is a simulated session (``tests.test_analysis_response.session``): the
simulator's gimbal, the ground station's commands, the decoder and the analysis.
"""

from __future__ import annotations

from typing import Any

import pytest

from analyzer.analysis.motion_fit import MIN_INTERVALS
from analyzer.api.analysis import analyze
from analyzer.commands.demo import DEMO_FAULTS
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.engine import SimConfig
from analyzer.sim.faults import FaultConfig
from analyzer.sim.ground import DEMO_PERIOD, Step, pilot_script
from analyzer.sim.offline import run_offline
from analyzer.sim.pilot import Stick
from tests.test_analysis_response import only, session

BAD = ("partial", "not_obeyed")


def rates(found: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [f for f in found if f["command"] == "gimbal_control" and f["check"] == "rate"]


def stick(at: float, length: float, pan: float = 0.0, tilt: float = 0.0, **kw: Any) -> Step:
    return Step(at, "gimbal_control", {}, until=at + length, stick=Stick(pan, tilt, **kw))


def test_the_demo_cut_mid_movement_gives_no_false_verdict() -> None:
    """`demo --duration 16 --stick --sluggish 0.4 --lag 0.3`: the second round of the
    demo's script begins 15 s in, and its first stick movement is cut by the end of the
    input. Before, it was 'NOT OBEYED ... the wrong way' from one feedback interval, the
    late gimbal's motion of the movement before falling into it."""
    script = pilot_script()
    steps = script + tuple(
        Step(s.at + DEMO_PERIOD, s.name, s.params, s.until and s.until + DEMO_PERIOD, s.stick)
        for s in script
    )
    config = SimConfig(
        uav=True,
        ranging=True,
        faults=FaultConfig(**DEMO_FAULTS),  # type: ignore[arg-type]
        behaviour=Behaviour(speed=0.4, lag_s=0.3),
    )
    _, events = run_offline(steps, 16.0, config, start=1_700_000_000.0)
    found = [f.fields for f in analyze(events)]
    moves = rates(found)
    assert not [f for f in moves if "wrong way" in f["detail"]]
    assert moves[0]["verdict"] == "partial" and "sluggish" in moves[0]["detail"]
    last = moves[-1]
    assert last["verdict"] == "unknown"
    assert last["detail"].startswith("the input ended ")
    assert " s into the movement: the motion it asked for cannot be judged" in last["detail"]
    # every verdict of the run is one the gimbal earned: sluggish, never the wrong way
    for f in found:
        if f["verdict"] in BAD and f["command"] == "gimbal_control":
            assert "sluggish" in f["detail"], f


@pytest.mark.parametrize(
    ("steps", "end", "words"),
    [
        (
            (stick(2.0, 3.0, pan=20.0, centred_s=0.5),),
            3.4,
            "the input ended 1.4 s into the movement",
        ),
        (
            (stick(2.0, 0.6, pan=30.0),),
            3.2,
            "the input ended 0.4 s after it, before its last motion could be seen "
            "(a gimbal may follow up to 1 s late)",
        ),
    ],
)
def test_a_movement_cut_by_the_end_of_the_input_is_unknown_with_the_reason(
    steps: tuple[Step, ...], end: float, words: str
) -> None:
    (rate,) = rates(session(steps, end))
    assert rate["verdict"] == "unknown"
    assert rate["detail"] == f"{words}: the motion it asked for cannot be judged"
    # the same movement seen to its end is judged
    (whole,) = rates(session(steps, 9.0))
    assert whole["verdict"] == "obeyed"


def test_a_movement_the_input_ends_after_is_judged_once_its_lag_is_measured() -> None:
    """The input ends 0.6 s after a 3 s movement: its fit measured the lag (none), and
    the feedback saw the gimbal past it."""
    (rate,) = rates(session((stick(2.0, 3.0, pan=20.0, centred_s=0.5),), 5.6))
    assert rate["verdict"] == "obeyed" and rate["lag_s"] == 0


def test_a_movement_cut_by_a_gap_in_the_feedback_is_unknown_with_the_reason() -> None:
    silent = FaultConfig(stop_at=3.5, stop_for=30.0)
    found = session((stick(2.0, 3.0, pan=20.0, centred_s=0.5),), 12.0, faults=silent)
    (rate,) = rates(found)
    assert rate["verdict"] == "unknown"
    assert rate["detail"].startswith("the feedback stopped 1.0 s into the movement")


def test_a_gap_the_feedback_comes_back_from_leaves_a_verdict() -> None:
    """Messages lost in the middle of a movement leave a longer interval, not a cut."""
    lost = FaultConfig(stop_at=3.1, stop_for=1.0)
    (rate,) = rates(session((stick(2.0, 4.0, pan=20.0, centred_s=0.5),), 12.0, faults=lost))
    assert rate["verdict"] == "obeyed" and rate["pan_ratio"] == pytest.approx(1, abs=0.05)


def test_no_verdict_from_fewer_intervals_than_the_fit_needs() -> None:
    """A 0.6 s movement that a target follows 0.3 s later: the gimbal may still be
    following it (up to 1 s late) when the target takes over, so the two feedback
    intervals that are its own cannot tell a lag from a ratio."""
    steps = (stick(2.0, 0.6, pan=30.0), Step(2.9, "specified_angle", {"pitch_deg": -30}))
    (rate,) = rates(session(steps, 10.0))
    assert rate["verdict"] == "unknown"
    assert f"fewer than {MIN_INTERVALS} feedback intervals" in rate["detail"]
    assert "until specified_angle came" in rate["detail"]


def test_a_short_movement_seen_whole_is_measured_by_its_whole_change() -> None:
    """The same 0.6 s movement with nothing after it: the feedback saw the gimbal still
    before and after it (past the longest lag), so its whole change is the answer, lag
    or none; a sluggish gimbal's is 40 %."""
    for speed, verdict in ((1.0, "obeyed"), (0.4, "partial")):
        found = session((stick(2.0, 0.6, pan=30.0),), 8.0, behaviour=Behaviour(speed=speed))
        (rate,) = rates(found)
        assert rate["verdict"] == verdict
        assert "over the whole movement" in rate["detail"]
        assert rate["pan_ratio"] == pytest.approx(speed, abs=0.05)
        assert "lag_s" not in rate


def test_a_late_gimbals_motion_is_counted_in_the_movement_that_caused_it() -> None:
    """Two movements of one stick, the second starting 0.2 s after the first ended,
    against a gimbal 0.6 s late: the first one's motion goes on into the second's time,
    and it is the first's (the second carries the commands just before it)."""
    steps = (
        stick(2.0, 2.0, pan=30.0, centred_s=0.2),
        stick(4.25, 2.5, pan=-20.0, centred_s=1.0),
    )
    found = session(steps, 14.0, behaviour=Behaviour(lag_s=0.6))
    first, second = rates(found)
    for rate in (first, second):
        assert rate["verdict"] == "obeyed", rate
        assert rate["pan_ratio"] == pytest.approx(1, abs=0.15)
    assert second["lag_s"] == pytest.approx(0.6, abs=0.1)
    assert "late" in second["detail"] and "wrong way" not in second["detail"]


def test_a_target_cut_by_a_gap_in_the_feedback_is_unknown_not_partial() -> None:
    """The feedback stops 0.6 s after a pitch target (the gimbal on its way) and comes
    back after the time allowed: where the gimbal was in the gap is not known."""
    steps = (Step(1.0, "specified_angle", {"pitch_deg": -90}),)
    gap = FaultConfig(stop_at=1.6, stop_for=6.0)
    target = only(session(steps, 12.0, faults=gap), "specified_angle", "target")
    assert target["verdict"] == "unknown"
    assert "the feedback stopped 0.5 s after it" in target["detail"]
    # the input ending on its way says so, with when (its last message, 0.5 s later)
    ended = only(session(steps, 1.8), "specified_angle", "target")
    assert ended["verdict"] == "unknown"
    assert "not at -90.0 yet when the input ended 0.5 s later" in ended["detail"]


def test_a_tracking_check_cut_by_the_feedback_stopping_is_unknown() -> None:
    steps = (Step(1.0, "tracking", {"x": 4096, "y": 4096, "width": 400, "height": 300}),)
    ignored = Behaviour(ignore=frozenset({"tracking"}))
    gap = FaultConfig(stop_at=1.2, stop_for=10.0)
    found = session(
        (*steps, Step(6.0, "zoom", {"action": "stop"})), 8.0, faults=gap, behaviour=ignored
    )
    check = only(found, "tracking", "tracking")
    assert check["verdict"] == "unknown"
    assert "(the feedback had stopped)" in check["detail"]


def test_a_drifting_gimbal_is_told_from_a_late_one() -> None:
    """Both turn on after the stick is let go at speed: the late one by as much as its
    fit says it follows late (the stop obeyed), the drifting one for longer."""
    steps = (stick(2.0, 3.0, pan=30.0, released=True, centred_s=3.0),)
    late = session(steps, 12.0, behaviour=Behaviour(lag_s=0.6))
    assert only(late, "gimbal_control", "stop")["verdict"] == "obeyed"
    assert "late" in only(late, "gimbal_control", "rate")["detail"]
    drifting = session(steps, 12.0, behaviour=Behaviour(drift_s=1.5))
    stop = only(drifting, "gimbal_control", "stop")
    assert stop["verdict"] == "not_obeyed" and "still moving" in stop["detail"]
