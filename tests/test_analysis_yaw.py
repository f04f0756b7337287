"""Yaw targets judged in the frame the command named: psi from north, or the motor from the nose.

Simulated sessions of a gimbal on an aircraft pointing at heading 30 (psi = 30 + motor
yaw), captured on the CAN bus (with and without the flight controller's attitude
0x0000FF13) and on the IDU's TCP link (where FF13 never travels).
"""

from __future__ import annotations

from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from analyzer.analysis.yaw_geometry import shortest_difference
from analyzer.protocol.types import (
    TOPIC_COMMAND,
    TOPIC_GIMBAL_ATTITUDE,
    Event,
)
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.engine import SimConfig
from analyzer.sim.ground import Step
from analyzer.sim.offline import run_offline, run_offline_stream
from tests.test_analysis_response import analyse  # the findings, each checked against the schema

HEADING = 30.0
OFFSET_30 = "psi offset from motor yaw: 30.0 deg"
WRONG_FRAME = Behaviour(geodetic_as_airframe=True)


def yaw_target(
    yaw: float,
    link: str = "can",
    *,
    airframe: bool = False,
    behaviour: Behaviour | None = None,
    **config: Any,
) -> dict[str, Any]:
    """The target finding of one specified_angle yaw command, captured on ``link``."""
    params: dict[str, Any] = {"yaw_deg": yaw}
    if airframe:
        params["coordinate_system"] = "airframe"
    steps = (Step(1.0, "specified_angle", params),)
    sim = SimConfig(behaviour=behaviour or Behaviour(), **config)
    run = run_offline if link == "can" else run_offline_stream
    _, events = run(steps, 8.0, sim)
    if link == "tcp":
        assert all(
            e.fields.get("transport") == "stream" for e in events if e.topic == TOPIC_COMMAND
        )
    found = [f for f in analyse(events) if f["check"] == "target"]
    assert len(found) == 1, found
    return found[0]


# -- which reference, and why --------------------------------------------------------------------


@pytest.mark.parametrize("link", ["can", "tcp"])
def test_a_geodetic_target_is_judged_on_psi_when_psi_is_offset_from_the_motor(link: str) -> None:
    f = yaw_target(45, link, heading_deg=HEADING)  # psi goes to 45, the motor to 15
    assert f["verdict"] == "obeyed", f["detail"]
    assert f["yaw_reference"] == "north" and f["reference_reason"] == OFFSET_30
    assert f["axis"] == "yaw" and f["final_deg"] == pytest.approx(45, abs=0.1)
    assert "stopped short" not in f["detail"]
    assert f"yaw measured from north ({OFFSET_30})" in f["detail"]


def test_a_geodetic_target_is_judged_on_psi_when_ff13_is_on_the_bus() -> None:
    f = yaw_target(45, heading_deg=HEADING, uav=True)
    assert f["verdict"] == "obeyed"
    assert f["yaw_reference"] == "north" and f["reference_reason"] == "FF13 present"


def test_a_gimbal_without_heading_on_can_is_judged_on_the_motor() -> None:
    f = yaw_target(45)  # no FF13, heading 0: psi equals the motor yaw
    assert f["verdict"] == "obeyed" and f["axis"] == "motor_yaw"
    assert f["yaw_reference"] == "airframe"
    assert f["reference_reason"] == "no FF13 on the bus; psi follows motor yaw"


def test_a_tcp_capture_cannot_tell_so_psi_is_used_and_the_finding_says_so() -> None:
    f = yaw_target(45, "tcp")
    assert f["verdict"] == "obeyed" and f["axis"] == "yaw"
    assert f["yaw_reference"] == "north"
    assert f["reference_reason"] == "capture shows no heading source; psi used"


@pytest.mark.parametrize("link", ["can", "tcp"])
def test_an_airframe_target_is_judged_on_the_motor(link: str) -> None:
    f = yaw_target(45, link, airframe=True, heading_deg=HEADING)  # motor 45, psi 75
    assert f["verdict"] == "obeyed" and f["axis"] == "motor_yaw"
    assert f["final_deg"] == pytest.approx(45, abs=0.1)
    assert f["yaw_reference"] == "airframe" and f["reference_reason"] == "command DATA4 = 1"


# -- the shortest way round ----------------------------------------------------------------------


@pytest.mark.parametrize("link", ["can", "tcp"])
def test_stopping_10_short_of_200_is_10_deg_not_320(link: str) -> None:
    short = Behaviour(reach=16 / 17)  # the motor stops at 160 of 170: psi 190
    f = yaw_target(200, link, heading_deg=HEADING, behaviour=short)
    assert f["verdict"] == "partial" and f["target_deg"] == 200
    assert f["error_deg"] == pytest.approx(10, abs=0.1)
    assert "stopped short at 190.0, 10.0 deg from the target" in f["detail"]
    assert "other way" not in f["detail"]


@pytest.mark.parametrize(("yaw", "airframe"), [(350, False), (350, True), (0, False)])
def test_targets_across_0_and_360(yaw: float, airframe: bool) -> None:
    f = yaw_target(yaw, airframe=airframe, heading_deg=HEADING)  # psi 30 -> 350 through 0
    assert f["verdict"] == "obeyed", f["detail"]
    assert f["target_deg"] == yaw  # as the command gave it, not -10
    assert abs(f["error_deg"]) <= 1.0


@pytest.mark.parametrize(
    ("yaw", "airframe", "limit", "error"),
    [(215, False, -170, -5), (180, True, -170, -10), (190, True, -170, 0)],
)
def test_a_target_beyond_the_motor_range_is_unreachable_by_the_motor(
    yaw: float, airframe: bool, limit: float, error: float
) -> None:
    f = yaw_target(yaw, airframe=airframe, heading_deg=HEADING)
    if error == 0:  # 190 from the nose is -170: the limit itself, reachable
        assert f["verdict"] == "obeyed" and f["target_deg"] == 190
        return
    assert f["verdict"] == "partial" and f["limit_deg"] == limit
    assert "out of the yaw motor's reach" in f["detail"] and "as near as it can get" in f["detail"]
    assert f["error_deg"] == pytest.approx(error, abs=0.1)
    assert "stopped short" not in f["detail"]


def test_an_airframe_target_of_200_is_the_motor_at_minus_160_and_stays_200() -> None:
    f = yaw_target(200, airframe=True, heading_deg=HEADING)
    assert f["verdict"] == "obeyed" and f["target_deg"] == 200
    assert f["final_deg"] == pytest.approx(-160, abs=0.1)


# -- the gimbal that takes geodetic targets from the nose ----------------------------------------


@pytest.mark.parametrize(
    ("link", "config", "reason"),
    [
        ("can", {"heading_deg": HEADING}, OFFSET_30),
        ("can", {"heading_deg": HEADING, "uav": True}, "FF13 present"),
        ("tcp", {"heading_deg": HEADING}, OFFSET_30),
    ],
)
def test_geodetic_taken_as_airframe_is_not_obeyed(
    link: str, config: dict[str, Any], reason: str
) -> None:
    f = yaw_target(45, link, behaviour=WRONG_FRAME, **config)  # motor 45, psi 75
    assert f["verdict"] == "not_obeyed" and f["reference_reason"] == reason
    assert "turned to 45.0 from the airframe's nose instead" in f["detail"]
    assert "as if DATA4 were 1" in f["detail"]
    assert f["error_deg"] == pytest.approx(-30, abs=0.1)
    assert "response_s" not in f


def test_the_fault_is_invisible_when_the_gimbal_has_no_heading() -> None:
    # Without a heading both frames are the same angle: nothing to tell them apart.
    f = yaw_target(45, behaviour=WRONG_FRAME)
    assert f["verdict"] == "obeyed" and f["yaw_reference"] == "airframe"


# -- the motor cannot pass its back stop ---------------------------------------------------------


def attitude(t: float, motor: float, heading: float = 0.0) -> Event:
    fields = {"pitch_deg": 0.0, "yaw_deg": (motor + heading) % 360, "motor_yaw_deg": motor}
    return Event(TOPIC_GIMBAL_ATTITUDE, t, "can0", {**fields, "tracking": False})


def turn(start: float, end: float, **command: Any) -> dict[str, Any]:
    """A yaw command at 1 s, the motor going from ``start`` to ``end`` in 3 s."""
    events = [attitude(0.5, start)]
    events.append(Event(TOPIC_COMMAND, 1.0, "can0", {"name": "specified_angle", **command}))
    events += [attitude(1.0 + 0.5 * i, start + (end - start) * min(i, 6) / 6) for i in range(1, 14)]
    return next(f for f in analyse(events) if f["check"] == "target")


def test_turning_the_long_way_round_the_back_stop_is_the_right_way() -> None:
    # From -100 to 120 the motor must turn +220: the shortest way (-140) crosses its stop.
    f = turn(-100, 60, axis="yaw", yaw_deg=120, coordinate_system="airframe")
    assert f["verdict"] == "partial" and "stopped short at 60.0" in f["detail"]
    f = turn(-100, 120, axis="yaw", yaw_deg=120, coordinate_system="airframe")
    assert f["verdict"] == "obeyed"


def test_moving_the_other_way_is_still_seen_and_its_error_is_short() -> None:
    # Geodetic 200 on a gimbal without heading: the motor should go to -160, went to +160.
    f = turn(0, 160, axis="yaw", yaw_deg=200, coordinate_system="geodetic")
    assert f["verdict"] == "not_obeyed" and "moved the other way" in f["detail"]
    assert f["error_deg"] == pytest.approx(40)


angles = st.floats(-720, 720, allow_nan=False)


@given(angles, angles)
def test_the_shortest_difference_is_within_half_a_turn(a: float, b: float) -> None:
    d = shortest_difference(a, b)
    assert -180 < d <= 180
    turns = (a - b - d) / 360
    assert turns == pytest.approx(round(turns), abs=1e-9)
