"""The simulated gimbal's physical model and feedback schedule, on simulated time."""

from __future__ import annotations

import math
from typing import Any

import pytest

from analyzer.protocol.codec import decode_command, encode_command
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.ids import ALTITUDE_ID, FEEDBACK_ID, GPS_ID, TEXT_END_ID, UAV_ATTITUDE_ID
from analyzer.protocol.types import (
    TOPIC_COMMAND,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_GIMBAL_RANGING,
    TOPIC_UAV_GPS,
    CanFrame,
    Event,
)
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.engine import SimConfig, SimulatedGimbal, describe_command
from analyzer.sim.model import HOLD_S, PITCH_MAX, PITCH_MIN, SLEW_DPS, GimbalModel
from analyzer.sim.uav import FlightPath, UavPlayer


def command(name: str, **params: Any) -> dict[str, Any]:
    """The fields a /gimbal/command event carries for this command."""
    fields, warnings = decode_command(encode_command(name, **params))
    assert warnings == []
    return fields


def hold(model: GimbalModel, fields: dict[str, Any], start: float, end: float) -> None:
    """Send a command every 50 ms from ``start`` to ``end``, as a ground station does."""
    t = start
    while t <= end + 1e-9:
        model.apply(fields, t)
        t = round(t + 0.05, 6)


def test_tilt_speed_integrates_into_pitch_while_repeated() -> None:
    model = GimbalModel(0.0)
    hold(model, command("gimbal_control", tilt_speed_dps=-10), 0.0, 1.0)
    model.step(1.0)
    assert model.pitch_deg == pytest.approx(-10.0)
    assert model.control_mode == 1  # full lock: speed controlled
    model.step(5.0)  # no more commands: it keeps turning HOLD_S longer, then stops
    assert model.pitch_deg == pytest.approx(-10.0 - 10 * HOLD_S)


def test_pan_speed_turns_yaw_and_motor_yaw() -> None:
    model = GimbalModel(0.0)
    model.uav.heading_deg = 350.0
    hold(model, command("gimbal_control", pan_speed_dps=20), 0.0, 1.0)
    model.step(1.0)
    assert model.motor_yaw_deg == pytest.approx(20.0)
    assert model.yaw_deg == pytest.approx(10.0)  # 350 + 20, wrapped into [0, 360)


def test_speeds_stop_at_the_limits_of_the_spec() -> None:
    model = GimbalModel(0.0)
    hold(model, command("gimbal_control", tilt_speed_dps=100, pan_speed_dps=100), 0.0, 2.0)
    model.step(2.0)
    assert model.pitch_deg == PITCH_MAX == 60.0
    assert model.motor_yaw_deg == 170.0
    hold(model, command("gimbal_control", tilt_speed_dps=-100), 2.0, 5.0)
    assert model.pitch_deg == PITCH_MIN == -110.0
    wide = GimbalModel(0.0, gimbal_type=3)  # 3.5x zoom: motor yaw up to 325 deg
    hold(wide, command("gimbal_control", pan_speed_dps=-100), 0.0, 4.0)
    assert wide.motor_yaw_deg == -325.0


def test_specified_angle_moves_at_a_realistic_rate_and_converges() -> None:
    model = GimbalModel(0.0)
    model.apply(command("specified_angle", pitch_deg=-45), 0.0)
    model.step(0.5)
    assert model.pitch_deg == pytest.approx(-SLEW_DPS * 0.5)
    model.step(2.0)
    assert model.pitch_deg == -45.0
    assert model.control_mode == 3  # locking: angle controlled


def test_geodetic_yaw_is_held_while_the_aircraft_turns() -> None:
    model = GimbalModel(0.0)
    model.uav.heading_deg = 30.0
    model.apply(command("specified_angle", yaw_deg=90), 0.0)
    model.step(3.0)
    assert model.yaw_deg == pytest.approx(90.0)
    assert model.motor_yaw_deg == pytest.approx(60.0)
    model.uav.heading_deg = 50.0
    model.step(4.0)
    assert model.yaw_deg == pytest.approx(90.0)
    airframe = GimbalModel(0.0)
    airframe.uav.heading_deg = 30.0
    airframe.apply(command("specified_angle", yaw_deg=90, coordinate_system="airframe"), 0.0)
    airframe.step(3.0)
    assert airframe.motor_yaw_deg == pytest.approx(90.0)
    assert airframe.yaw_deg == pytest.approx(120.0)


def test_look_down_forward_and_tracking() -> None:
    model = GimbalModel(0.0)
    model.apply(command("look_down"), 0.0)
    model.step(3.0)
    assert model.pitch_deg == -90.0
    model.apply(command("tracking", x=4096, y=4096, width=320, height=320), 3.0)
    assert model.tracking
    model.apply(command("tracking_stop"), 3.1)
    assert not model.tracking
    model.apply(command("tracking", s_id=0x1F, x=4096, y=4096), 3.2)
    assert model.tracking
    model.apply(command("tracking_stop", s_id=0x1F), 3.3)
    assert not model.tracking
    hold(model, command("gimbal_control", pan_speed_dps=30), 3.3, 4.3)
    model.apply(command("forward"), 5.0)
    model.step(10.0)
    assert (model.pitch_deg, model.motor_yaw_deg) == (0.0, 0.0)


def test_zoom_commands() -> None:
    model = GimbalModel(0.0)
    model.apply(command("zoom", action="zoom_in"), 0.0)
    model.step(1.0)
    assert model.zoom > 2.0
    model.apply(command("zoom", action="stop"), 1.0)
    stopped = model.zoom
    model.step(2.0)
    assert model.zoom == stopped
    model.apply(command("specified_angle", zoom=10), 2.0)
    model.step(10.0)
    assert model.zoom == 10.0
    model.apply(command("zoom", action="zoom_out_2x"), 10.0)
    model.step(12.0)
    assert model.zoom == 5.0
    model.apply(command("zoom_1x"), 12.0)
    model.step(20.0)
    assert model.zoom == 1.0


def test_commands_without_an_effect_on_feedback_are_noted_and_unknown_ones_ignored() -> None:
    model = GimbalModel(0.0)
    assert model.apply(command("recording", action="start"), 0.0)
    assert model.recording
    assert model.apply(command("palette", palette="iron_red"), 0.0)
    assert model.last_action == "palette iron_red"
    unknown, _ = decode_command(bytes.fromhex("0F 7E 00 00 00 00 00 00"))
    assert not model.apply(unknown, 0.0)
    assert (model.commands, model.ignored) == (2, 1)


def test_ranging_points_where_the_line_of_sight_meets_the_ground() -> None:
    model = GimbalModel(0.0)
    model.uav.altitude_m = 100.0
    model.apply(command("specified_angle", pitch_deg=-45), 0.0)
    model.step(2.0)
    ranging = model.ranging()
    assert ranging["success"]
    assert ranging["distance_m"] == pytest.approx(100 * math.sqrt(2))
    assert ranging["latitude_deg"] > model.uav.latitude_deg  # yaw 0: due north
    model.apply(command("forward"), 2.0)
    model.step(4.0)
    assert not model.ranging()["success"]  # looking at the horizon: no ground hit


def drive(gimbal: SimulatedGimbal, until: float, step: float = 0.01) -> list[Event]:
    """Poll the simulator on simulated time and decode what it sends, as the analyzer does."""
    decoder = ProtocolDecoder()
    events: list[Event] = []
    t = 0.0
    while t <= until:
        for can_id, data in gimbal.poll(t):
            events.extend(decoder.feed(CanFrame(t, can_id, data)))
        t = round(t + step, 6)
    return events + decoder.close(t)


def test_attitude_feedback_every_500_ms_with_good_crc_and_the_model_values() -> None:
    gimbal = SimulatedGimbal(0.0)
    gimbal.handle(Event(TOPIC_COMMAND, 0.0, "t", command("specified_angle", pitch_deg=-30)), 0.0)
    events = drive(gimbal, 3.0)
    attitudes = [e for e in events if e.topic == TOPIC_GIMBAL_ATTITUDE]
    assert [e.time for e in attitudes] == pytest.approx([0.5 * i for i in range(7)])
    assert all(not e.warnings for e in events)
    assert attitudes[-1].fields["pitch_deg"] == -30.0
    assert attitudes[1].fields["pitch_deg"] == -30.0  # 60 deg/s: there after 0.5 s
    assert attitudes[0].fields["control_mode_code"] == 3


def test_feedback_is_sent_as_four_8_byte_segments_on_the_feedback_id() -> None:
    gimbal = SimulatedGimbal(0.0)
    frames = gimbal.poll(0.0)
    assert [cid for cid, _ in frames] == [FEEDBACK_ID] * 4
    assert [len(d) for _, d in frames] == [8] * 4
    assert frames[0][1][:3] == bytes.fromhex("EB 90 0C")


def test_ranging_and_uav_play_along() -> None:
    gimbal = SimulatedGimbal(0.0, SimConfig(ranging=True, uav=True))
    events = drive(gimbal, 6.0)
    topics = {e.topic for e in events}
    assert {TOPIC_GIMBAL_RANGING, TOPIC_UAV_GPS, "/uav/altitude", "/uav/attitude"} <= topics
    assert next(e for e in events if e.topic == "/uav/text").fields["text"] == "UAV armed"
    assert all(not e.warnings for e in events), [e.warnings for e in events if e.warnings]
    gps = [e for e in events if e.topic == TOPIC_UAV_GPS]
    assert len(gps) == pytest.approx(6 / 0.2, abs=2)


def test_uav_flight_path_orbits_and_climbs() -> None:
    path = FlightPath()
    start, _, _ = path.pose(0.0)
    later, pitch, roll = path.pose(1000.0)
    assert start.altitude_m == 0.0 and later.altitude_m == path.cruise_altitude_m
    assert pitch == 0.0 and roll > 0
    player = UavPlayer(0.0, path)
    ids = [cid for cid, _ in player.due(0.0)]
    assert ids[:3] == [GPS_ID, ALTITUDE_ID, UAV_ATTITUDE_ID] and ids[-1] == TEXT_END_ID
    assert player.due(0.05) == []


def test_uav_frames_received_steer_the_geodetic_frame_when_the_uav_is_not_played() -> None:
    gimbal = SimulatedGimbal(0.0)
    gimbal.handle(Event("/uav/attitude", 0.0, "t", {"yaw_deg": 45.0}), 0.0)
    gimbal.handle(Event(TOPIC_UAV_GPS, 0.0, "t", {"latitude_deg": 1.5, "longitude_deg": 2.5}), 0)
    assert gimbal.model.uav.heading_deg == 45.0
    assert (gimbal.model.uav.latitude_deg, gimbal.model.uav.longitude_deg) == (1.5, 2.5)
    assert gimbal.model.yaw_deg == 45.0


def test_describe_command_is_one_readable_line() -> None:
    text = describe_command(command("gimbal_control", pan_speed_dps=-5))
    assert text == "gimbal_control pan_speed_dps=-5 tilt_speed_dps=0"
    assert describe_command(command("palette", palette="iron_red")) == (
        "palette (dual_sensor) palette=iron_red"
    )


def test_a_heading_offsets_psi_from_the_motor_and_the_uav_keeps_its_nose_there() -> None:
    alone = SimulatedGimbal(0.0, SimConfig(heading_deg=30.0))
    alone.handle(Event(TOPIC_COMMAND, 0.0, "t", command("specified_angle", yaw_deg=45)), 0.0)
    last = [e for e in drive(alone, 3.0) if e.topic == TOPIC_GIMBAL_ATTITUDE][-1].fields
    assert last["yaw_deg"] == pytest.approx(45.0) and last["motor_yaw_deg"] == pytest.approx(15.0)
    flying = SimulatedGimbal(0.0, SimConfig(heading_deg=30.0, uav=True))
    events = drive(flying, 3.0)
    headings = {e.fields["yaw_deg"] for e in events if e.topic == "/uav/attitude"}
    assert headings == {30.0}  # FF13 says 30 all along, while the aircraft orbits
    assert len({e.fields["latitude_deg"] for e in events if e.topic == TOPIC_UAV_GPS}) > 1
    assert FlightPath(heading_deg=200.0).pose(5.0)[0].heading_deg == -160.0  # FF13's s16 range


def test_a_gimbal_that_takes_geodetic_targets_from_the_nose() -> None:
    model = GimbalModel(0.0, behaviour=Behaviour(geodetic_as_airframe=True))
    model.uav.heading_deg = 30.0
    model.apply(command("specified_angle", yaw_deg=45), 0.0)
    model.step(3.0)
    assert model.motor_yaw_deg == pytest.approx(45.0) and model.yaw_deg == pytest.approx(75.0)
    assert "takes geodetic yaw targets from the airframe's nose" in model.behaviour.describe()


def test_a_gimbal_that_turns_the_wrong_way_for_speeds() -> None:
    model = GimbalModel(0.0, behaviour=Behaviour(wrong_way=True))
    hold(model, command("gimbal_control", pan_speed_dps=20, tilt_speed_dps=-10), 0.0, 1.0)
    model.step(1.0)
    assert model.motor_yaw_deg == pytest.approx(-20.0) and model.pitch_deg == pytest.approx(10.0)
    model.apply(command("specified_angle", pitch_deg=-30), 1.0)  # angles it gets right
    model.step(3.0)
    assert model.pitch_deg == pytest.approx(-30.0)
    assert "turns the other way for gimbal_control speeds" in model.behaviour.describe()


def test_a_drifting_gimbal_turns_on_after_a_stop_however_often_it_is_told() -> None:
    model = GimbalModel(0.0, behaviour=Behaviour(drift_s=1.0))
    hold(model, command("gimbal_control", pan_speed_dps=20), 0.0, 1.0)
    hold(model, command("gimbal_control", pan_speed_dps=0), 1.05, 4.0)  # zeros at 20 Hz
    assert model.motor_yaw_deg == pytest.approx(20.0 * 2.05)  # 1 s more after the first 0
    model.step(6.0)  # and no longer
    assert model.motor_yaw_deg == pytest.approx(20.0 * 2.05)


def test_a_frozen_gimbal_and_one_left_off_centre() -> None:
    frozen = SimulatedGimbal(0.0, SimConfig(behaviour=Behaviour(speed=0.0), attitude=(-45, 120)))
    frozen.model.apply(command("forward"), 0.0)
    frozen.model.step(5.0)
    assert (frozen.model.pitch_deg, frozen.model.motor_yaw_deg) == (-45.0, 120.0)
    assert frozen.model.behaviour.describe() == "does not move at all (frozen)"
    beyond = SimulatedGimbal(0.0, SimConfig(attitude=(-200, 400)))  # kept within the range
    assert (beyond.model.pitch_deg, beyond.model.motor_yaw_deg) == (PITCH_MIN, 170.0)
