"""Did the gimbal obey? Each finding from simulated sessions, obeyed and every way of not obeying."""

from __future__ import annotations

from typing import Any

import jsonschema
import pytest

from analyzer.analysis.response import ResponseAnalyzer, Settings
from analyzer.protocol.schema import topic_schemas
from analyzer.protocol.types import (
    TOPIC_ANALYSIS_RESPONSE,
    TOPIC_COMMAND,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_UAV_ATTITUDE,
    Event,
)
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.engine import SimConfig
from analyzer.sim.faults import FaultConfig
from analyzer.sim.ground import Step
from analyzer.sim.offline import run_offline

VALIDATOR = jsonschema.Draft202012Validator(topic_schemas()[TOPIC_ANALYSIS_RESPONSE])


def analyse(events: list[Event], settings: Settings | None = None) -> list[dict[str, Any]]:
    analyzer = ResponseAnalyzer(settings)
    out: list[Event] = []
    for event in events:
        out += analyzer.feed(event)
    out += analyzer.close()
    found = [e.to_dict() for e in out]
    for finding in found:
        VALIDATOR.validate(finding)
        assert None not in finding.values()
        assert finding["detail"].strip()
    return found


def session(
    steps: tuple[Step, ...], duration: float, settings: Settings | None = None, **config: Any
) -> list[dict[str, Any]]:
    behaviour = config.pop("behaviour", Behaviour())
    _, events = run_offline(steps, duration, SimConfig(behaviour=behaviour, **config))
    return analyse(events, settings)


def only(found: list[dict[str, Any]], command: str, check: str) -> dict[str, Any]:
    matches = [f for f in found if f["command"] == command and f["check"] == check]
    assert len(matches) == 1, found
    return matches[0]


YAW_45 = (Step(1.0, "specified_angle", {"yaw_deg": 45}),)
PITCH_DOWN = (Step(1.0, "specified_angle", {"pitch_deg": -45}),)


# -- specified_angle ----------------------------------------------------------------------------


def test_specified_yaw_obeyed_with_time_and_final_error() -> None:
    f = only(session(YAW_45, 8.0), "specified_angle", "target")
    assert f["verdict"] == "obeyed"
    assert f["time"] == pytest.approx(1.0)
    assert f["target_deg"] == 45
    assert 0.5 <= f["response_s"] <= 1.5  # 45 deg at 60 deg/s, feedback every 500 ms
    assert abs(f["error_deg"]) <= 1.0
    assert f["yaw_reference"] == "airframe"
    assert "airframe's nose" in f["detail"]


def test_specified_pitch_obeyed() -> None:
    f = only(session(PITCH_DOWN, 8.0), "specified_angle", "target")
    assert f["verdict"] == "obeyed" and f["target_deg"] == -45 and "pitch reached" in f["detail"]
    assert "yaw_reference" not in f


def test_yaw_from_north_when_the_flight_controller_attitude_is_present() -> None:
    f = only(session(YAW_45, 8.0, uav=True), "specified_angle", "target")
    assert f["yaw_reference"] == "north" and "from north" in f["detail"]
    assert f["verdict"] == "obeyed"  # the simulator holds the geodetic heading


def test_never_moved_when_the_gimbal_ignores_specified_angle() -> None:
    ignoring = Behaviour(ignore=frozenset({"specified_angle"}))
    f = only(session(YAW_45, 8.0, behaviour=ignoring), "specified_angle", "target")
    assert f["verdict"] == "not_obeyed"
    assert "not reached within 5 s" in f["detail"] and "never moved" in f["detail"]
    assert f["error_deg"] == pytest.approx(45, abs=0.1)
    assert "response_s" not in f


def test_stops_short() -> None:
    short = Behaviour(reach=0.6)
    f = only(session(PITCH_DOWN, 8.0, behaviour=short), "specified_angle", "target")
    assert f["verdict"] == "partial" and "stopped short" in f["detail"]
    assert f["error_deg"] == pytest.approx(-18, abs=0.2)  # target -45, stopped at -27


def test_sluggish_gimbal_misses_the_time_allowed_but_is_on_its_way() -> None:
    slow = Behaviour(speed=0.1)  # 6 deg/s: 45 deg take 7.5 s
    f = only(session(PITCH_DOWN, 8.0, behaviour=slow), "specified_angle", "target")
    assert f["verdict"] == "partial" and "still on its way" in f["detail"]


def test_time_allowed_and_tolerance_are_settings() -> None:
    slow = Behaviour(speed=0.1)
    settings = Settings(tolerance_deg=2.0, time_allowed_s=9.0)
    f = only(session(PITCH_DOWN, 12.0, settings, behaviour=slow), "specified_angle", "target")
    assert f["verdict"] == "obeyed" and 6.5 <= f["response_s"] <= 8.0
    with pytest.raises(ValueError):
        Settings(tolerance_deg=0)


def test_target_outside_the_pitch_range_ends_at_the_limit() -> None:
    steps = (Step(1.0, "specified_angle", {"pitch_deg": 60}),)
    found = session(steps, 8.0)
    f = only(found, "specified_angle", "target")
    assert f["verdict"] == "obeyed"  # 60 is the upper limit itself
    limit = only(found, "specified_angle", "limit")
    assert limit["limit_deg"] == 60 and limit["verdict"] == "partial"


def test_a_later_command_on_the_same_axis_cuts_the_judgement_short() -> None:
    steps = (*YAW_45, Step(1.3, "specified_angle", {"yaw_deg": 90}))
    found = [f for f in session(steps, 8.0) if f["check"] == "target"]
    assert [f["verdict"] for f in found] == ["unknown", "obeyed"]
    assert "specified_angle came 0.3 s later" in found[0]["detail"]


def test_a_command_on_the_other_axis_does_not_cut_it_short() -> None:
    steps = (*YAW_45, Step(1.3, "specified_angle", {"pitch_deg": -20}))
    found = [f for f in session(steps, 8.0) if f["check"] == "target"]
    assert [f["verdict"] for f in found] == ["obeyed", "obeyed"]


# -- synthetic feedback: what the simulator never does ------------------------------------------


def attitude(
    t: float, pitch: float = 0.0, yaw: float = 0.0, motor: float = 0.0, **kw: Any
) -> Event:
    fields = {"pitch_deg": pitch, "yaw_deg": yaw, "motor_yaw_deg": motor, "tracking": False}
    fields.update(kw)
    return Event(TOPIC_GIMBAL_ATTITUDE, t, "can0", fields)


def command(t: float, name: str, **fields: Any) -> Event:
    return Event(TOPIC_COMMAND, t, "can0", {"name": name, **fields})


def test_moved_the_other_way() -> None:
    events = [attitude(0.5, pitch=-10)]
    events.append(command(1.0, "specified_angle", axis="pitch", pitch_deg=-45))
    events += [attitude(1.0 + 0.5 * i, pitch=-10 + 3 * i) for i in range(1, 13)]
    f = only(analyse(events), "specified_angle", "target")
    assert f["verdict"] == "not_obeyed" and "moved the other way" in f["detail"]


def test_overshoot_is_measured() -> None:
    events = [attitude(0.5, pitch=0), command(1.0, "look_down")]
    events += [attitude(t, pitch=p) for t, p in ((1.5, -60), (2.0, -97), (2.5, -91), (3.0, -90))]
    events += [attitude(3.0 + 0.5 * i, pitch=-90) for i in range(1, 8)]
    f = only(analyse(events), "look_down", "target")
    assert f["verdict"] == "obeyed" and f["overshoot_deg"] == pytest.approx(7)
    assert "overshooting by 7.0 deg" in f["detail"] and f["response_s"] == pytest.approx(1.0)


def test_yaw_is_compared_modulo_360() -> None:
    events = [Event(TOPIC_UAV_ATTITUDE, 0.4, "can0", {"yaw_deg": 10.0}), attitude(0.5, yaw=20)]
    events.append(command(1.0, "specified_angle", axis="yaw", yaw_deg=0, coordinate_system="x"))
    events += [attitude(1.0 + 0.5 * i, yaw=(20 - 10 * i) % 360) for i in range(1, 3)]
    events += [attitude(2.0 + 0.5 * i, yaw=359.5) for i in range(1, 10)]
    f = only(analyse(events), "specified_angle", "target")
    assert f["verdict"] == "obeyed" and f["error_deg"] == pytest.approx(0.5)
    assert f["yaw_reference"] == "north"


def test_airframe_yaw_when_the_command_asks_for_it() -> None:
    events = [Event(TOPIC_UAV_ATTITUDE, 0.4, "can0", {"yaw_deg": 10.0}), attitude(0.5)]
    events.append(
        command(1.0, "specified_angle", axis="yaw", yaw_deg=350, coordinate_system="airframe")
    )
    events += [attitude(1.0 + 0.5 * i, motor=-10.0, yaw=0.0) for i in range(1, 12)]
    f = only(analyse(events), "specified_angle", "target")
    assert f["verdict"] == "obeyed" and f["target_deg"] == 350  # as commanded, not -10
    assert f["yaw_reference"] == "airframe" and f["reference_reason"] == "command DATA4 = 1"
    assert "from the airframe's nose (command DATA4 = 1)" in f["detail"]


def test_no_feedback_at_all_is_unknown() -> None:
    events = [command(1.0, "look_down"), command(2.0, "tracking", x=1, y=1)]
    events.append(Event("/uav/gps", 9.0, "can0", {"latitude_deg": 1.0}))
    found = analyse(events)
    assert {f["verdict"] for f in found} == {"unknown"}
    assert "no gimbal feedback in the input" in only(found, "feedback", "feedback")["detail"]


def test_input_ending_before_the_time_allowed_is_unknown_unless_reached() -> None:
    events = [attitude(0.5), command(1.0, "look_down"), attitude(1.5, pitch=-30)]
    f = only(analyse(events), "look_down", "target")
    assert f["verdict"] == "unknown" and "the input ended" in f["detail"]


# -- look_down, forward --------------------------------------------------------------------------

LOOK_DOWN = (Step(1.0, "look_down"),)
FORWARD = (Step(0.5, "specified_angle", {"pitch_deg": -30}), Step(1.0, "forward"))


def test_look_down_obeyed_and_ignored() -> None:
    f = only(session(LOOK_DOWN, 8.0), "look_down", "target")
    assert f["verdict"] == "obeyed" and f["target_deg"] == -90
    ignoring = Behaviour(ignore=frozenset({"look_down"}))
    f = only(session(LOOK_DOWN, 8.0, behaviour=ignoring), "look_down", "target")
    assert f["verdict"] == "not_obeyed" and "never moved" in f["detail"]


def test_forward_obeyed_and_stopping_short() -> None:
    steps = (Step(0.5, "specified_angle", {"yaw_deg": 60}), *FORWARD[1:])
    steps = (Step(0.2, "specified_angle", {"pitch_deg": -60}), *steps)
    steps = tuple(Step(s.at * 4, s.name, s.params) for s in steps)  # let each move finish
    f = only(session(steps, 10.0), "forward", "target")
    assert f["verdict"] == "obeyed" and f["target_deg"] == 0 and "pitch reached" in f["detail"]
    short = session(steps, 10.0, behaviour=Behaviour(reach=0.5))
    f = only(short, "forward", "target")
    assert f["verdict"] == "partial" and "stopped short" in f["detail"]


# -- tracking ------------------------------------------------------------------------------------

TRACK = (
    Step(1.0, "tracking", {"x": 4096, "y": 4096, "width": 320, "height": 240}),
    Step(4.0, "tracking_stop"),
)


def test_tracking_start_and_stop_follow_the_flag() -> None:
    found = session(TRACK, 8.0)
    start, stop = only(found, "tracking", "tracking"), only(found, "tracking_stop", "tracking")
    assert start["verdict"] == stop["verdict"] == "obeyed"
    assert 0 < start["response_s"] <= 0.6 and "went on" in start["detail"]
    assert "went off" in stop["detail"]


def test_tracking_never_engaged_is_not_obeyed_after_three_feedback_periods() -> None:
    # The flag stays off in every feedback message: not obeyed once 1.5 s (three periods
    # at 2 Hz) have passed, also when the next command (the stop, 3 s later) follows.
    found = session(TRACK, 8.0, behaviour=Behaviour(ignore=frozenset({"tracking"})))
    f = only(found, "tracking", "tracking")
    assert f["verdict"] == "not_obeyed" and "stayed off through the 1.5 s allowed" in f["detail"]
    assert f["observed_at"] - f["time"] <= 1.5
    stop = only(found, "tracking_stop", "tracking")
    assert stop["verdict"] == "unknown" and "tracking was never on" in stop["detail"]
    found = session(TRACK[:1], 8.0, behaviour=Behaviour(ignore=frozenset({"tracking"})))
    f = only(found, "tracking", "tracking")
    assert f["verdict"] == "not_obeyed" and "stayed off through the 1.5 s" in f["detail"]


def test_the_flag_allowance_is_a_setting() -> None:
    ignored = Behaviour(ignore=frozenset({"tracking"}))
    found = session(TRACK, 8.0, Settings(flag_allowed_s=2.5), behaviour=ignored)
    assert "stayed off through the 2.5 s allowed" in only(found, "tracking", "tracking")["detail"]
    # A stop before the allowance is over cuts the check short: not known.
    found = session(TRACK, 8.0, Settings(flag_allowed_s=4.0), behaviour=ignored)
    f = only(found, "tracking", "tracking")
    assert f["verdict"] == "unknown" and "until tracking_stop came 3.0 s later" in f["detail"]
    with pytest.raises(ValueError, match="state flag"):
        Settings(flag_allowed_s=0)


def test_stopping_tracking_that_never_started_is_never_obeyed() -> None:
    found = session((Step(1.0, "tracking_stop"),), 5.0)
    f = only(found, "tracking_stop", "tracking")
    assert f["verdict"] == "unknown" and f["detail"].startswith("tracking was never on")
    # Started, then stopped twice: the second stop has nothing left to stop.
    twice = (*TRACK, Step(6.0, "tracking_stop"))
    found = [f for f in session(twice, 9.0) if f["command"] == "tracking_stop"]
    assert [f["verdict"] for f in found] == ["obeyed", "unknown"]
    assert "tracking was already off" in found[1]["detail"]


def test_tracking_that_does_not_stop() -> None:
    found = session(TRACK, 12.0, behaviour=Behaviour(ignore=frozenset({"tracking_stop"})))
    f = only(found, "tracking_stop", "tracking")
    assert f["verdict"] == "not_obeyed" and "stayed on through the 1.5 s" in f["detail"]


# -- gimbal_control ------------------------------------------------------------------------------

PAN = (Step(1.0, "gimbal_control", {"pan_speed_dps": 20}, until=3.0),)


def test_rate_obeyed_and_it_stops() -> None:
    found = session(PAN, 8.0)
    rate = only(found, "gimbal_control", "rate")
    assert rate["verdict"] == "obeyed" and rate["pan_ratio"] == pytest.approx(1, abs=0.05)
    assert rate["measured_pan_dps"] == pytest.approx(20, rel=0.05)
    assert rate["commanded_pan_dps"] == 20 and rate["peak_pan_dps"] == 20
    assert rate["rate_ratio"] == rate["pan_ratio"] and "tilt_ratio" not in rate
    assert rate["command_count"] == 41 and "lag_s" in rate
    assert rate["interval_mean_s"] == pytest.approx(0.05) and rate["component"] == "gimbal"
    stop = only(found, "gimbal_control", "stop")
    assert stop["verdict"] == "obeyed" and "stopped when the commands stopped" in stop["detail"]
    assert not [f for f in found if f["check"] == "repeat"]  # every 50 ms


def test_sluggish_rate() -> None:
    found = session(PAN, 8.0, behaviour=Behaviour(speed=0.4))
    rate = only(found, "gimbal_control", "rate")
    assert rate["verdict"] == "partial" and "sluggish" in rate["detail"]
    assert rate["rate_ratio"] == pytest.approx(0.4, abs=0.05)


def test_ignored_speed_commands() -> None:
    found = session(PAN, 8.0, behaviour=Behaviour(ignore=frozenset({"gimbal_control"})))
    rate = only(found, "gimbal_control", "rate")
    assert rate["verdict"] == "not_obeyed" and "hardly moved" in rate["detail"]


def test_still_moving_after_the_commands_stopped() -> None:
    found = session(PAN, 8.0, behaviour=Behaviour(drift_s=1.5))
    stop = only(found, "gimbal_control", "stop")
    assert stop["verdict"] == "not_obeyed" and "still moving" in stop["detail"]
    assert stop["time"] == pytest.approx(3.0, abs=0.06)
    assert 1.0 <= stop["duration_s"] <= 2.0 and stop["moved_deg"] > 10


def test_commands_repeated_too_slowly() -> None:
    steps = tuple(Step(1.0 + 0.4 * i, "gimbal_control", {"tilt_speed_dps": -10}) for i in range(6))
    found = session(steps, 8.0)
    repeat = only(found, "gimbal_control", "repeat")
    assert repeat["interval_mean_s"] == pytest.approx(0.4, abs=0.01)
    assert repeat["interval_max_s"] == pytest.approx(0.4, abs=0.01)
    assert repeat["command_count"] == 6 and "recommends 50 ms" in repeat["detail"]
    # Each command turned it for the 0.3 s it holds, as the commands asked: the rate is
    # obeyed, and the cadence is what the finding names.
    assert only(found, "gimbal_control", "rate")["verdict"] == "obeyed"
    once = session(steps[:1], 8.0)
    assert "sent once" in only(once, "gimbal_control", "repeat")["detail"]


def test_commands_repeated_too_slowly_for_a_gimbal_that_stops_at_once() -> None:
    """A gimbal that obeys each command only briefly turns less than the commands ask
    when they come every 0.4 s: the rate is partial and the cadence says why."""
    steps = tuple(Step(1.0 + 0.4 * i, "gimbal_control", {"tilt_speed_dps": -10}) for i in range(8))
    found = session(steps, 8.0, behaviour=Behaviour(speed=0.3))
    rate = only(found, "gimbal_control", "rate")
    assert rate["verdict"] == "partial" and rate["tilt_ratio"] == pytest.approx(0.3, abs=0.05)
    assert only(found, "gimbal_control", "repeat")["verdict"] == "partial"


def test_an_explicit_zero_speed_ends_the_burst() -> None:
    steps = (*PAN, Step(3.05, "gimbal_control", {"pan_speed_dps": 0}))
    stop = only(session(steps, 8.0), "gimbal_control", "stop")
    assert stop["time"] == pytest.approx(3.05) and stop["verdict"] == "obeyed"


def test_speed_into_the_limit() -> None:
    steps = (Step(0.5, "gimbal_control", {"tilt_speed_dps": -60}, until=3.0),)
    found = session(steps, 6.0)
    limit = only(found, "gimbal_control", "limit")
    assert limit["limit_deg"] == -110 and limit["axis"] == "pitch"
    assert "at its pitch limit -110.0" in limit["detail"]
    assert only(found, "gimbal_control", "rate")["verdict"] == "obeyed"
    assert not [f for f in session(PAN, 8.0) if f["check"] == "limit"]


# -- feedback health -----------------------------------------------------------------------------


def test_healthy_feedback() -> None:
    f = only(session(LOOK_DOWN, 30.0), "feedback", "feedback")
    assert f["verdict"] == "healthy" and f["feedback_hz"] == pytest.approx(2, abs=0.1)
    assert f["crc_errors"] == 0 and f["gaps"] == 0


def test_feedback_silence_and_crc_errors() -> None:
    faults = FaultConfig(corrupt=0.02, stop_at=5.0, stop_for=3.0, seed=3)
    found = session(LOOK_DOWN, 70.0, faults=faults)
    gaps = [f for f in found if f["check"] == "feedback_gap"]
    (outage,) = [f for f in gaps if f["gap_s"] > 2]
    assert 3.0 <= outage["gap_s"] <= 3.6 and outage["time"] == pytest.approx(4.5, abs=0.1)
    assert outage["lost_messages"] == 6 and "6 messages missing" in outage["detail"]
    assert outage["verdict"] == "lost"
    # A corrupted message came: it is damaged, not also lost (no silence around it).
    assert [f for f in gaps if f is not outage] == []
    windows = [f for f in found if f["check"] == "feedback"]
    assert len(windows) == 2  # one per minute
    assert windows[0]["verdict"] == "degraded" and windows[0]["crc_errors"] > 0
    first = [f for f in gaps if f["time"] < windows[1]["time"]]
    lost = sum(f["lost_messages"] for f in first)
    assert windows[0]["gaps"] == len(first) and windows[0]["lost_messages"] == lost
    assert (len(first), lost) == (1, 6) and "1 gap (6 messages lost)" in windows[0]["detail"]


def test_simulate_options_make_the_behaviour() -> None:
    from analyzer.cli import build_parser
    from analyzer.commands.simulate import behaviour
    from analyzer.errors import UsageError

    parse = build_parser().parse_args
    args = parse(["simulate", "--sluggish", "0.4", "--fall-short", "70%", "--ignore", "tracking"])
    made = behaviour(args)
    assert made == Behaviour(speed=0.4, reach=0.7, ignore=frozenset({"tracking"}))
    assert "ignores tracking" in made.describe()
    assert behaviour(parse(["simulate"])) == Behaviour()
    with pytest.raises(UsageError, match="not a command name"):
        behaviour(parse(["simulate", "--ignore", "dance"]))


def test_a_settled_answer_is_judged_even_when_the_next_command_comes_early() -> None:
    steps = (*YAW_45, Step(4.0, "specified_angle", {"yaw_deg": 90}))
    found = session(steps, 12.0, behaviour=Behaviour(reach=0.5))
    first = next(f for f in found if f["check"] == "target")
    assert first["verdict"] == "partial" and "stopped short" in first["detail"]
    assert "not reached before specified_angle came 3.0 s later" in first["detail"]


def test_a_movement_shorter_than_the_feedback_period_is_measured_across_it() -> None:
    """0.3 s of commands between two feedback messages 0.5 s apart: the messages before
    and after it still measure the motion it asked for."""
    steps = (Step(1.0, "gimbal_control", {"pan_speed_dps": 20}, until=1.3),)
    rate = only(session(steps, 6.0), "gimbal_control", "rate")
    assert rate["verdict"] == "obeyed" and rate["pan_ratio"] == pytest.approx(1, abs=0.1)


def test_a_movement_with_no_feedback_after_it_is_not_measured() -> None:
    steps = (Step(1.0, "gimbal_control", {"pan_speed_dps": 20}, until=1.3),)
    faults = FaultConfig(stop_at=0.6, stop_for=10.0)
    rate = only(session(steps, 6.0, faults=faults), "gimbal_control", "rate")
    assert rate["verdict"] == "unknown"
    assert rate["detail"] == (
        "the feedback stopped 0.5 s before the movement: the motion it asked for cannot be judged"
    )


def test_a_clock_that_jumps_by_years_is_not_a_window_per_minute() -> None:
    events = [attitude(0.0), attitude(1_700_000_000.0), attitude(1_700_000_000.5)]
    windows = [f for f in analyse(events) if f["check"] == "feedback"]
    assert len(windows) == 2
