"""The generated ArduPilot mount driver, run on the emulated autopilot against the simulated
gimbal in virtual time: its frames decoded by our decoder are the commands each target and
camera action asks for, the attitude it reports is the feedback's, damage is dropped. Each
test runs twice: in lupa's Lua 5.3 and in Lua built as ArduPilot builds it (32-bit numbers,
its limits), and across millis()'s wraps."""

from __future__ import annotations

import itertools
import json
import math
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

from analyzer.analysis.response import ResponseAnalyzer
from analyzer.ardupilot.plan import CameraStep, MountStep, offset_from
from analyzer.ardupilot.script import compile_check
from analyzer.ardupilot.session import Session, run_session
from analyzer.export.ardupilot import DRIVER_NAME, lua_text
from analyzer.protocol.types import (
    TOPIC_ARDUPILOT_MOUNT,
    TOPIC_ARDUPILOT_TARGETS,
    TOPIC_COMMAND,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_UAV_ALTITUDE,
    TOPIC_UAV_ATTITUDE,
    TOPIC_UAV_GPS,
    Event,
)
from analyzer.sim.engine import SimConfig
from analyzer.sim.faults import FaultConfig
from analyzer.sim.uav import FlightPath
from tests.ardupilot_lua import ardupilot_lua

# Lua built as ArduPilot builds it (seconds, once per process) and demos of the driver.
pytestmark = pytest.mark.slow

__all__ = ["ardupilot_lua"]  # the fixture

CLEAN = SimConfig(ranging=True)
LUA: ModuleType | None = None  # the interpreter of the test that runs


@pytest.fixture(autouse=True, params=["lupa", "ardupilot"])
def interpreter(request: pytest.FixtureRequest) -> Iterator[None]:
    global LUA
    LUA = None if request.param == "lupa" else request.getfixturevalue("ardupilot_lua")
    yield
    LUA = None


def run(plan: tuple[Any, ...], duration: float, **options: Any) -> Session:
    options.setdefault("config", CLEAN)
    options.setdefault("lua", LUA)
    session = run_session(lua_text(), DRIVER_NAME, duration, plan=plan, period=None, **options)
    assert session.error is None, session.error
    return session


def commands(session: Session, start: float = 0.0, end: float = 1e9) -> list[Event]:
    return [e for e in session.events if e.topic == TOPIC_COMMAND and start <= e.time < end]


def named(events: list[Event], name: str) -> list[dict[str, Any]]:
    return [e.fields for e in events if e.fields["name"] == name]


def test_generated_driver_compiles_under_lua_5_3_and_is_the_same_every_time() -> None:
    text = lua_text()
    compile_check(text, DRIVER_NAME)
    assert text == lua_text()
    assert text.startswith(f"-- {DRIVER_NAME}: ")
    assert "Set MNT1_TYPE = 9" in text and "CAN_D1_PROTOCOL = 10" in text


def test_rate_targets_become_gimbal_control_every_50_ms_and_one_stop() -> None:
    plan = (
        MountStep(0.5, "rate", pitch=-20.0, yaw=10.0),
        MountStep(2.0, "rate"),  # the stick back in the middle
        MountStep(3.0, "rate", yaw=-30.0),
        MountStep(4.0, "none"),  # the mount library asks nothing
    )
    session = run(plan, 5.0)
    first = named(commands(session, 0.5, 2.0), "gimbal_control")
    assert {(c["pan_speed_dps"], c["tilt_speed_dps"]) for c in first} == {(10.0, -20.0)}
    times = [e.time for e in commands(session, 0.5, 2.0)]
    gaps = {round(b - a, 3) for a, b in itertools.pairwise(times)}
    assert gaps == {0.05} and len(times) == 30
    stop = named(commands(session, 2.0, 3.0), "gimbal_control")
    assert stop == [stop[0]] and (stop[0]["pan_speed_dps"], stop[0]["tilt_speed_dps"]) == (0, 0)
    after = named(commands(session, 4.0), "gimbal_control")
    assert [(c["pan_speed_dps"], c["tilt_speed_dps"]) for c in after] == [(0, 0)]


def test_angle_targets_become_specified_angle_airframe_or_geodetic() -> None:
    plan = (
        MountStep(0.2, "angle", pitch=-30.0, yaw=-60.0),
        MountStep(2.0, "angle", pitch=-30.0, yaw=-60.0, yaw_is_earth_frame=True),
        MountStep(4.0, "angle", pitch=10.0, yaw=200.0, yaw_is_earth_frame=True),
    )
    session = run(plan, 6.0)
    angles = [
        (c["axis"], c.get("pitch_deg", c.get("yaw_deg")), c["coordinate_system"])
        for c in named(commands(session), "specified_angle")
    ]
    assert angles == [
        ("pitch", -30.0, "geodetic"),  # DATA4 is not read for pitch
        ("yaw", 300.0, "airframe"),  # -60 from the nose, as the 0..360 the command takes
        ("yaw", 300.0, "geodetic"),  # the same number, now from north: sent again
        ("pitch", 10.0, "geodetic"),
        ("yaw", 200.0, "geodetic"),
    ]


def test_a_location_target_becomes_the_angles_to_it_from_the_aircraft() -> None:
    path = FlightPath(speed_mps=0.0, climb_mps=50.0, cruise_altitude_m=100.0)  # hovering
    plan = (MountStep(0.5, "location", north_m=-100.0, east_m=100.0),)
    session = run(plan, 3.0, path=path)
    sent = named(commands(session), "specified_angle")
    first = next(e for e in commands(session) if e.fields["name"] == "specified_angle")
    pose, _, _ = path.pose(first.time)
    home = (path.home_latitude_deg, path.home_longitude_deg)
    lat, lon = offset_from(home, -100.0, 100.0)
    north = (lat - pose.latitude_deg) * 111_318.845
    east = (lon - pose.longitude_deg) * 111_318.845 * math.cos(math.radians(lat))
    want_yaw = math.degrees(math.atan2(east, north)) % 360
    want_pitch = -math.degrees(math.atan2(pose.altitude_m, math.hypot(north, east)))
    yaw = next(c for c in sent if c["axis"] == "yaw")
    pitch = next(c for c in sent if c["axis"] == "pitch")
    assert yaw["coordinate_system"] == "geodetic"
    assert yaw["yaw_deg"] == pytest.approx(want_yaw, abs=0.11)
    assert pitch["pitch_deg"] == pytest.approx(want_pitch, abs=0.11)


def test_camera_actions_become_the_camera_commands() -> None:
    plan = (
        CameraStep(0.5, "take_picture"),
        CameraStep(1.0, "record_start"),
        CameraStep(1.5, "zoom_rate", value=1.0),
        CameraStep(2.0, "zoom_rate", value=-1.0),
        CameraStep(2.5, "zoom_rate", value=0.0),
        CameraStep(3.0, "zoom_percent", value=50.0),
        CameraStep(3.5, "focus_rate", value=1.0),
        CameraStep(4.0, "focus_auto"),
        CameraStep(4.5, "track_point", x=0.25, y=0.75),
        CameraStep(5.0, "track_rectangle", x=0.1, y=0.2, x2=0.3, y2=0.6),
        CameraStep(5.5, "track_stop"),
        CameraStep(6.0, "record_stop"),
    )
    session = run(plan, 7.0)
    seen = [
        (c["name"], c.get("mode") or c.get("action") or c.get("zoom") or c.get("x"))
        for c in (e.fields for e in commands(session))
    ]
    assert seen == [
        ("snapshot", "single"),
        ("recording", "start"),
        ("zoom", "zoom_in"),
        ("zoom", "zoom_out"),
        ("zoom", "stop"),
        ("specified_angle", 15.5),  # 50 % of 1x .. 30x (VSH_ZOOM_MAX)
        ("focus", "focus_plus"),
        ("focus", "auto_focus"),
        ("tracking", 2048),  # 0.25 of 0..8191
        ("tracking", 1638),
        ("tracking_stop", None),
        ("recording", "stop"),
    ]
    point, box = named(commands(session), "tracking")
    assert (point["y"], point["width"], point["height"]) == (6143, 512, 512)
    assert (box["y"], box["width"], box["height"]) == (3276, 1632, 3280)  # sizes in 16 px


def test_the_attitude_reported_is_the_feedbacks_pitch_and_motor_yaw() -> None:
    plan = (MountStep(0.2, "angle", pitch=-40.0, yaw=-70.0), MountStep(3.0, "rate", yaw=20.0))
    session = run(plan, 6.0)
    feedback = [e for e in session.events if e.topic == TOPIC_GIMBAL_ATTITUDE]
    reports = [e for e in session.events if e.topic == TOPIC_ARDUPILOT_MOUNT]
    assert len(reports) == len(feedback) >= 10
    for fb, report in zip(feedback, reports, strict=True):
        assert report.fields["roll_deg"] == 0
        assert report.fields["pitch_deg"] == pytest.approx(fb.fields["pitch_deg"], abs=1e-4)
        assert report.fields["yaw_deg"] == pytest.approx(fb.fields["motor_yaw_deg"], abs=1e-4)
    assert any(r.fields["yaw_deg"] < -60 for r in reports)


@pytest.mark.slow
def test_damaged_feedback_is_dropped_and_reported_to_the_gcs() -> None:
    faults = FaultConfig(corrupt=0.15, drop=0.1, seed=3)
    session = run((), 20.0, config=SimConfig(faults=faults))
    good = [e for e in session.events if e.topic == TOPIC_GIMBAL_ATTITUDE]
    reports = [e for e in session.events if e.topic == TOPIC_ARDUPILOT_MOUNT]
    assert session.gimbal is not None and session.gimbal.faults.counts["corrupt"] > 0
    # only what our reassembler accepts reaches the mount library
    assert len(reports) == len(good) < session.gimbal.sent["attitude"]
    texts = [text for _, _, text in session.vehicle.texts]
    assert any(text.startswith("VSH: feedback dropped:") for text in texts), texts
    assert all(len(text) <= 50 for text in texts)


def test_a_silent_gimbal_neither_blocks_nor_crashes_the_driver() -> None:
    session = run((MountStep(0.5, "angle", pitch=-20.0),), 10.0, gimbal=False)
    assert session.script.due_ms is not None  # still scheduled: it keeps running
    texts = [text for _, _, text in session.vehicle.texts]
    assert texts.count("VSH: no feedback from the gimbal") == 1
    status = Counter(e.topic for e in session.events if e.time >= 1.0)
    assert status[TOPIC_UAV_ATTITUDE] >= 85 and status[TOPIC_UAV_GPS] >= 40
    assert named(commands(session), "specified_angle")  # targets go out all the same


@pytest.mark.slow
def test_uav_status_goes_out_at_5_hz_or_more_from_the_ahrs_and_the_gps() -> None:
    path = FlightPath(heading_deg=30.0)
    session = run((), 10.0, path=path)
    per_topic = Counter(e.topic for e in session.events if 2.0 <= e.time < 10.0)
    assert per_topic[TOPIC_UAV_ATTITUDE] >= 8 * 10
    assert per_topic[TOPIC_UAV_GPS] >= 8 * 5 and per_topic[TOPIC_UAV_ALTITUDE] >= 8 * 5
    for event in session.events:
        pose, pitch, roll = path.pose(event.time)
        if event.topic == TOPIC_UAV_ATTITUDE:
            assert event.fields["yaw_deg"] == pytest.approx(30.0, abs=0.01)
            assert event.fields["pitch_deg"] == pytest.approx(pitch, abs=0.01)
            assert event.fields["roll_deg"] == pytest.approx(roll, abs=0.01)
        elif event.topic == TOPIC_UAV_GPS:
            assert event.fields["latitude_deg"] == pytest.approx(pose.latitude_deg, abs=1e-7)
            assert event.fields["longitude_deg"] == pytest.approx(pose.longitude_deg, abs=1e-7)
        elif event.topic == TOPIC_UAV_ALTITUDE:
            assert event.fields["altitude_m"] == pytest.approx(pose.altitude_m, abs=0.01)
        assert not event.warnings, event


def test_nothing_outside_the_documents_ranges_whatever_is_asked() -> None:
    plan = (
        MountStep(0.2, "rate", pitch=-500.0, yaw=900.0),
        MountStep(1.0, "angle", pitch=-170.0, yaw=720.5),
        MountStep(2.0, "angle", pitch=80.0, yaw=-400.0, yaw_is_earth_frame=True),
        CameraStep(2.5, "zoom_percent", value=250.0),
        CameraStep(3.0, "track_rectangle", x=-1.0, y=0.0, x2=3.0, y2=5.0),
    )
    session = run(plan, 4.0)
    sent = commands(session)
    assert len(sent) >= 10
    assert [e.warnings for e in sent if e.warnings] == []
    speeds = named(sent, "gimbal_control")[0]
    assert (speeds["pan_speed_dps"], speeds["tilt_speed_dps"]) == (100.0, -100.0)
    pitches = [c["pitch_deg"] for c in named(sent, "specified_angle") if "pitch_deg" in c]
    assert pitches == [-100.0, 60.0]


def test_only_the_scripting_can_driver_it_is_given() -> None:
    second = {"VSH_CAN_DRV": 2, "CAN_D1_PROTOCOL": 0, "CAN_D2_PROTOCOL": 12}
    session = run((MountStep(0.2, "angle", pitch=-10.0),), 2.0, parameters=second)
    assert list(session.vehicle.devices) == [2] and session.sent
    assert session.script.log.calls[("CAN", "get_device", 1)] == 0
    # asked for the second driver where only the first is a scripting one: silence
    missing = run((), 4.0, parameters={"VSH_CAN_DRV": 2})
    assert missing.sent == [] and missing.vehicle.devices == {}
    assert "VSH: no scripting CAN driver 2" in [t for _, _, t in missing.vehicle.texts]


@pytest.mark.slow
def test_the_demo_plan_is_obeyed_as_analyze_judges_it() -> None:
    session = run_session(lua_text(), DRIVER_NAME, 40.0, lua=LUA)  # two rounds of the plan
    assert session.error is None
    analyzer = ResponseAnalyzer()
    events = [e for e in session.events if not e.topic.startswith("/ardupilot")]
    findings = [{**f.fields, "time": f.time} for f in analyzer.process(events) + analyzer.close()]
    angles = [
        f
        for f in findings
        if f["command"] == "specified_angle" and f["check"] == "target" and f["time"] < 20.0
    ]
    assert len(angles) >= 12  # the first round; in the second the point to look at is
    # behind the orbiting aircraft at times, out of the yaw motor's reach
    assert {f["verdict"] for f in angles} == {"obeyed"}, [f["detail"] for f in angles]
    assert not [f for f in findings if f["verdict"] == "not_obeyed"]
    targets = [e for e in session.events if e.topic == TOPIC_ARDUPILOT_TARGETS]
    assert {e.fields["target"] for e in targets} == {"rate", "none", "angle", "location", "camera"}


@pytest.mark.slow
def test_a_dataflash_log_of_the_flight_is_judged_the_same(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from analyzer.cli import main
    from tests.log_makers import ardupilot_log

    boot = 1_795_834_800.0
    session = run_session(lua_text(), DRIVER_NAME, 12.0, start=boot + 40.0, lua=LUA)
    log, _ = ardupilot_log(session.frames, boot)  # CANF records, as LogAllFrames writes
    path = tmp_path / "00000042.BIN"
    path.write_bytes(log)
    assert main(["analyze", str(path), "--json"]) == 0
    found = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    angles = [f for f in found if f["command"] == "specified_angle" and f["check"] == "target"]
    settled = [f for f in angles if f["time"] < boot + 40.0 + 9.0]  # not cut by the log's end
    assert len(settled) >= 4 and {f["verdict"] for f in settled} == {"obeyed"}
    assert not [f for f in found if f["verdict"] == "not_obeyed"]


@pytest.mark.parametrize("boot_ms", [2**31 - 3000, 2**32 - 3000, 2**31 + 1000, 2**32 + 500])
def test_the_schedule_and_the_feedback_hold_across_the_wraps_of_millis(boot_ms: int) -> None:
    """millis() passes 2^31 (toint() turns negative) or wraps at 2^32 three seconds in, or
    the script starts past either: the status keeps its schedule, feedback keeps coming."""
    session = run((MountStep(0.5, "angle", pitch=-20.0),), 8.0, boot_ms=boot_ms)
    for topic, period in ((TOPIC_UAV_ATTITUDE, 0.1), (TOPIC_UAV_GPS, 0.2)):
        times = [e.time for e in session.events if e.topic == topic]
        assert {round(b - a, 3) for a, b in itertools.pairwise(times)} == {period}, topic
        assert times[0] == 0.0 and times[-1] >= 7.8
    feedback = [e for e in session.events if e.topic == TOPIC_GIMBAL_ATTITUDE]
    reports = [e for e in session.events if e.topic == TOPIC_ARDUPILOT_MOUNT]
    assert len(reports) == len(feedback) >= 12
    texts = [text for _, _, text in session.vehicle.texts]
    assert texts == ["VSH: mount driver started"]
    silent = run((), 6.0, boot_ms=boot_ms, gimbal=False)
    lost = [(t, text) for t, _, text in silent.vehicle.texts if "no feedback" in text]
    assert lost == [(pytest.approx(2.01), "VSH: no feedback from the gimbal")]
