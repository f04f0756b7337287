"""Where the gimbal points and what it was told to look at, as Foxglove draws it.

The views are made from frames decoded by the real decoder: /tf puts the gimbal's x axis
where the camera looks (elevation = pitch, azimuth = the yaw motor's angle, under an
aircraft turned and tilted by the UAV status), the overlays put the tracking box of the
``tracking`` command (0..8191 picture units) on the stream's pixels, and every message
matches Foxglove's own JSON Schema.
"""

from __future__ import annotations

import json
import math
from fractions import Fraction
from typing import Any

import av
import jsonschema
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from analyzer.mcapio.foxglove import FoxgloveViews, view_schema
from analyzer.mcapio.read.video import Thumbnail
from analyzer.mcapio.scene_views import TOPIC_SCENE, TOPIC_TF
from analyzer.protocol.codec import encode_command
from analyzer.protocol.command_table import COMMANDS
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.feedback import encode_attitude, encode_ranging, segments
from analyzer.protocol.ids import ALTITUDE_ID, CONTROL_ID, FEEDBACK_ID, GPS_ID, UAV_ATTITUDE_ID
from analyzer.protocol.types import CanFrame, Event
from analyzer.protocol.uav import encode_altitude, encode_gps, encode_uav_attitude
from analyzer.scene.geometry import (
    Quaternion,
    Vector,
    azimuth_elevation,
    gimbal_rotation,
    multiply,
    rotate,
    yaw_pitch_roll,
)
from analyzer.scene.overlays import box_corners, overlay, text_place
from analyzer.scene.scene3d import HFOV_1X_DEG, field_of_view
from analyzer.scene.state import SCENE_COMMANDS, Box, GimbalState
from analyzer.scene.stroke_font import GLYPHS, text_segments
from analyzer.scene.timeline import OverlayTimeline

ANNOTATIONS = "/camera/main/annotations"
THUMBNAIL_ANNOTATIONS = "/camera/main/thumbnail/annotations"
VALIDATORS = {
    topic: jsonschema.Draft202012Validator(view_schema(topic)[1])
    for topic in (
        TOPIC_TF,
        TOPIC_SCENE,
        ANNOTATIONS,
        THUMBNAIL_ANNOTATIONS,
        "/uav/gps/fix",
        "/gimbal/ranging/fix",
    )
}


class Bench:
    """A decoder and the views of a recording with a 1920x1080 stream (thumbnail 320x180)."""

    def __init__(self) -> None:
        self.decoder = ProtocolDecoder()
        self.views = FoxgloveViews()
        self.views.scene.add_camera("main")
        self.views.scene.add_overlay(ANNOTATIONS, 1920, 1080)
        self.views.scene.add_overlay(THUMBNAIL_ANNOTATIONS, 320, 180, stroked=True)
        self.time = 1_700_000_000.0
        self.sent: dict[str, list[dict[str, Any]]] = {}

    def frames(self, can_id: int, *payloads: bytes) -> list[Event]:
        self.time += 0.05
        events = []
        for payload in payloads:
            events += self.decoder.feed_can(CanFrame(self.time, can_id, payload))
        for event in events:
            for topic, message in self.views.views(event):
                message = json.loads(json.dumps(message))
                VALIDATORS[topic].validate(message)
                self.sent.setdefault(topic, []).append(message)
        return events

    def command(self, name: str, **fields: Any) -> None:
        (event,) = self.frames(CONTROL_ID, encode_command(name, **fields))
        assert event.fields["name"] == name

    def feedback(self, pitch: float, motor_yaw: float, yaw: float = 0.0, **more: Any) -> None:
        message = encode_attitude(pitch_deg=pitch, yaw_deg=yaw, motor_yaw_deg=motor_yaw, **more)
        (event,) = self.frames(FEEDBACK_ID, *segments(message))
        assert event.topic == "/gimbal/attitude"

    def uav(self, heading: float, pitch: float = 0.0, roll: float = 0.0) -> None:
        yaw = heading if heading <= 180 else heading - 360  # s16 centidegrees: +-327 deg
        self.frames(UAV_ATTITUDE_ID, encode_uav_attitude(pitch, roll, yaw))

    def last(self, topic: str) -> dict[str, Any]:
        return self.sent[topic][-1]


def transforms(bench: Bench) -> dict[str, tuple[str, Quaternion, Vector]]:
    """child frame -> (parent, rotation, translation) of the last /tf message."""
    out = {}
    for t in bench.last(TOPIC_TF)["transforms"]:
        r, p = t["rotation"], t["translation"]
        out[t["child_frame_id"]] = (
            t["parent_frame_id"],
            Quaternion(r["x"], r["y"], r["z"], r["w"]),
            Vector(p["x"], p["y"], p["z"]),
        )
    return out


def in_world(bench: Bench, frame: str) -> Quaternion:
    tree = transforms(bench)
    q = Quaternion(0.0, 0.0, 0.0, 1.0)
    while frame in tree:
        parent, rotation, _ = tree[frame]
        q = multiply(rotation, q)
        frame = parent
    assert frame == "world"
    return q


def angle_difference(a: float, b: float) -> float:
    return abs((a - b + 180.0) % 360.0 - 180.0)


# -- transforms ---------------------------------------------------------------------------------


@settings(max_examples=60, deadline=None)
@given(
    heading=st.floats(0, 359.99),
    uav_pitch=st.floats(-30, 30),
    uav_roll=st.floats(-30, 30),
    pitch=st.floats(-85, 30),  # straight down, the azimuth is not defined
    motor_yaw=st.floats(-170, 170),
)
def test_the_gimbal_x_axis_points_where_the_feedback_says(
    heading: float, uav_pitch: float, uav_roll: float, pitch: float, motor_yaw: float
) -> None:
    bench = Bench()
    bench.uav(heading, uav_pitch, uav_roll)
    bench.feedback(pitch, motor_yaw)
    tree = transforms(bench)
    parent, gimbal, _ = tree["gimbal"]
    assert parent == "uav"
    # under the aircraft: elevation = the pitch, azimuth = the yaw motor's angle
    azimuth, elevation = azimuth_elevation(rotate(gimbal, Vector(1, 0, 0)))
    assert abs(elevation - pitch) < 0.5
    assert angle_difference(azimuth, motor_yaw) < 0.5
    # the aircraft in the east/north/up world: its nose along the heading, raised by its pitch
    parent, aircraft, _ = tree["uav"]
    assert parent == "world"
    from_east, nose_up = azimuth_elevation(rotate(aircraft, Vector(1, 0, 0)))
    assert angle_difference(from_east + 90.0, heading) < 0.5  # bearing: clockwise from north
    assert abs(nose_up - uav_pitch) < 0.5
    # the right wing goes down with a positive roll (yaw, then pitch, then roll)
    right_wing = rotate(aircraft, Vector(0, -1, 0))
    roll = math.degrees(math.asin(-right_wing.z / math.cos(math.radians(uav_pitch))))
    assert abs(roll - uav_roll) < 0.5


@given(azimuth=st.floats(-720, 720), elevation=st.floats(-180, 180))
@example(azimuth=0.0, elevation=-30.0)
@example(azimuth=-0.0, elevation=0.0)
def test_the_gimbal_rotation_multiplied_out_is_the_product_of_its_turns(
    azimuth: float, elevation: float
) -> None:
    product = yaw_pitch_roll(math.radians(-azimuth), math.radians(-elevation), 0.0)
    # the same floats, the sign of a zero included: the recording's /tf is unchanged
    assert repr(gimbal_rotation(azimuth, elevation)) == repr(product)


@pytest.mark.parametrize(("heading", "motor_yaw", "pitch"), [(30, 20, -45), (300, -90, 10)])
def test_on_a_level_aircraft_the_camera_looks_at_heading_plus_motor_yaw(
    heading: float, motor_yaw: float, pitch: float
) -> None:
    bench = Bench()
    bench.uav(heading)
    bench.feedback(pitch, motor_yaw, yaw=(heading + motor_yaw) % 360)
    sight = rotate(in_world(bench, "gimbal"), Vector(1, 0, 0))
    from_east, elevation = azimuth_elevation(sight)
    assert angle_difference(from_east + 90.0, heading + motor_yaw) < 0.5
    assert abs(elevation - pitch) < 0.5
    # the optical frame's z (into the picture) is the line of sight, its y points down
    optical = in_world(bench, "camera_main")
    along = rotate(optical, Vector(0, 0, 1))
    assert math.dist(along, sight) < 1e-9
    down = rotate(optical, Vector(0, 1, 0))
    assert down.z < 0 or pitch < -80


def test_without_uav_status_the_gimbal_hangs_under_a_fixed_base() -> None:
    bench = Bench()
    bench.feedback(-30.0, 45.0)
    tree = transforms(bench)
    assert tree["base"] == ("world", Quaternion(0, 0, 0, 1), Vector(0, 0, 0))
    assert tree["gimbal"][0] == "base"
    azimuth, elevation = azimuth_elevation(rotate(tree["gimbal"][1], Vector(1, 0, 0)))
    assert abs(azimuth - 45.0) < 0.5 and abs(elevation + 30.0) < 0.5
    assert set(tree) == {"base", "gimbal", "camera_main"}


def test_transforms_come_with_every_feedback_at_its_time() -> None:
    bench = Bench()
    bench.uav(0.0)
    bench.frames(GPS_ID, encode_gps(31.0, 118.0))
    for n in range(3):
        bench.feedback(-10.0 * n, 0.0)
        stamp = bench.last(TOPIC_TF)["transforms"][0]["timestamp"]
        assert stamp["sec"] + stamp["nsec"] / 1e9 == pytest.approx(bench.time, abs=1e-6)
    assert len(bench.sent[TOPIC_TF]) == 3
    bench.uav(10.0)  # UAV status alone moves nothing: the transforms follow the feedback
    assert len(bench.sent[TOPIC_TF]) == 3


def test_the_aircraft_is_placed_east_north_of_its_first_fix() -> None:
    bench = Bench()
    bench.uav(0.0)
    bench.frames(GPS_ID, encode_gps(31.0, 118.0))
    bench.frames(GPS_ID, encode_gps(31.001, 118.001))
    bench.feedback(0.0, 0.0)
    _, _, at = transforms(bench)["uav"]
    assert at.y == pytest.approx(111.2, abs=0.5)  # 0.001 deg of latitude
    assert at.x == pytest.approx(111.2 * math.cos(math.radians(31.0)), abs=0.5)


# -- the 3D scene ---------------------------------------------------------------------------


def entity(bench: Bench, name: str) -> dict[str, Any] | None:
    found = [e for e in bench.last(TOPIC_SCENE)["entities"] if e["id"] == name]
    return found[0] if found else None


def test_the_field_of_view_narrows_with_the_zoom_and_reaches_the_laser_target() -> None:
    bench = Bench()
    bench.feedback(-20.0, 0.0)
    assert entity(bench, "aircraft")["frame_id"] == "base"  # type: ignore[index]
    bench.command("specified_angle", axis="zoom", zoom=4.0)
    hfov, vfov = field_of_view(4.0, 1920 / 1080)
    assert hfov == pytest.approx(2 * math.degrees(math.atan(math.tan(math.radians(30)) / 4)))
    fov = entity(bench, "field_of_view")
    assert fov is not None and fov["frame_id"] == "gimbal" and fov["frame_locked"]
    corner = fov["lines"][0]["points"][1]
    assert math.degrees(math.atan2(corner["y"], corner["x"])) == pytest.approx(hfov / 2, abs=0.01)
    assert math.degrees(math.atan2(corner["z"], corner["x"])) == pytest.approx(vfov / 2, abs=0.01)
    assert entity(bench, "ranging_target") is None
    message = encode_ranging(distance_m=123.4, height_m=0, latitude_deg=31, longitude_deg=118)
    bench.frames(FEEDBACK_ID, *segments(message))
    target = entity(bench, "ranging_target")
    assert target is not None
    assert target["spheres"][0]["pose"]["position"]["x"] == pytest.approx(123.4)
    assert entity(bench, "field_of_view")["lines"][0]["points"][1]["x"] == pytest.approx(123.4)  # type: ignore[index]
    failed = encode_ranging(
        distance_m=0, height_m=0, latitude_deg=0, longitude_deg=0, success=False
    )
    bench.frames(FEEDBACK_ID, *segments(failed))
    assert entity(bench, "ranging_target") is None
    assert bench.last(TOPIC_SCENE)["deletions"][0]["id"] == "ranging_target"
    assert field_of_view(None)[0] == pytest.approx(HFOV_1X_DEG)  # unknown zoom: drawn at 1x


# -- overlays on the picture ------------------------------------------------------------------


def box_pixels(message: dict[str, Any]) -> tuple[float, float, float, float]:
    (box,) = [p for p in message["points"] if p["type"] == 2 and p["fill_color"]["a"] == 0]
    xs = [p["x"] for p in box["points"]]
    ys = [p["y"] for p in box["points"]]
    return min(xs), min(ys), max(xs), max(ys)


def test_the_tracking_box_is_drawn_on_the_stream_pixels_until_tracking_stops() -> None:
    bench = Bench()
    bench.feedback(-45.0, 0.0, yaw=90.0)
    assert bench.last(ANNOTATIONS)["points"] == []
    bench.command("tracking", x=4096, y=2048, width=800, height=400)
    left, top, right, bottom = box_pixels(bench.last(ANNOTATIONS))
    assert (left + right) / 2 == pytest.approx(4096 / 8191 * 1920, abs=0.01)
    assert (top + bottom) / 2 == pytest.approx(2048 / 8191 * 1080, abs=0.01)
    assert right - left == pytest.approx(800 / 8191 * 1920, abs=0.02)
    assert bottom - top == pytest.approx(400 / 8191 * 1080, abs=0.02)
    # the thumbnail's overlay is the same box scaled to 320 x 180
    left, top, right, bottom = box_pixels(bench.last(THUMBNAIL_ANNOTATIONS))
    assert (left + right) / 2 == pytest.approx(4096 / 8191 * 320, abs=0.01)
    assert bottom - top == pytest.approx(400 / 8191 * 180, abs=0.02)
    # it stays while the gimbal tracks, and goes when its flag goes off
    bench.feedback(-45.0, 0.0, tracking=False)
    bench.feedback(-45.0, 0.0, tracking=True)
    assert box_pixels(bench.last(ANNOTATIONS))
    bench.feedback(-45.0, 0.0, tracking=False)
    assert bench.last(ANNOTATIONS)["points"] == []
    # ... or when tracking_stop is sent
    bench.command("tracking", x=100, y=8000, width=160, height=160)
    assert box_pixels(bench.last(ANNOTATIONS))[3] == pytest.approx(8080 / 8191 * 1080, abs=0.02)
    bench.command("tracking_stop")
    assert bench.last(ANNOTATIONS)["points"] == []


def test_only_the_scene_commands_change_what_is_drawn() -> None:
    """Every other command of the table is skipped by the views: none of them, with every
    field a scene command reads, changes the state or gives a view."""
    reads = {"x": 100, "y": 100, "width": 50, "height": 50, "x_pct": 10, "y_pct": 10}
    reads |= {"action": "zoom_1x", "axis": "zoom", "zoom": 3.0}
    names = {row.name for row in COMMANDS}
    assert names >= SCENE_COMMANDS
    for name in sorted(names - SCENE_COMMANDS):
        state = GimbalState(zoom=2.0)
        event = Event("/gimbal/command", 1.0, "can0", {"name": name, **reads})
        assert state.observe(event) == ""
        assert state == GimbalState(zoom=2.0), name
        assert FoxgloveViews().views(event) == [], name
    for name in sorted(SCENE_COMMANDS):  # each of them does change it, given its fields
        state = GimbalState(zoom=2.0, box=Box(1, 1, 1, 1))
        event = Event("/gimbal/command", 1.0, "can0", {"name": name, **reads})
        assert state.observe(event) == "command", name


def test_taps_are_marked_where_they_were_sent_for_a_while() -> None:
    bench = Bench()
    bench.feedback(0.0, 0.0)
    bench.command("tap_zoom", x_pct=25.0, y_pct=-10.0)
    (circle,) = bench.last(ANNOTATIONS)["circles"]
    assert circle["position"] == {"x": 0.625 * 1920, "y": 0.45 * 1080}
    bench.command("tap_focus", x=8191, y=0)
    circles = bench.last(ANNOTATIONS)["circles"]
    assert circles[1]["position"] == {"x": 1920, "y": 0}
    bench.time += 3.0
    bench.feedback(0.0, 0.0)
    assert bench.last(ANNOTATIONS)["circles"] == []


def test_the_text_line_says_pitch_yaw_and_zoom_with_each_feedback() -> None:
    bench = Bench()
    bench.feedback(-45.0, 0.0, yaw=90.0)
    assert bench.last(ANNOTATIONS)["texts"][0]["text"] == "P -45.0  Y 90.0  Z ?"
    bench.command("specified_angle", axis="zoom", zoom=2.0)
    bench.feedback(-44.5, 0.0, yaw=91.25)
    (text,) = bench.last(ANNOTATIONS)["texts"]
    assert text["text"] == "P -44.5  Y 91.2  Z 2.0x" or text["text"] == "P -44.5  Y 91.3  Z 2.0x"
    bench.command("zoom", action="zoom_in_2x")
    assert bench.last(ANNOTATIONS)["texts"][0]["text"].endswith("Z 4.0x")
    bench.command("zoom", action="zoom_in")  # continuous: where it stops is not said
    assert bench.last(ANNOTATIONS)["texts"][0]["text"].endswith("Z ?")
    bench.command("zoom_1x")
    assert bench.last(ANNOTATIONS)["texts"][0]["text"].endswith("Z 1.0x")
    assert len(bench.sent[ANNOTATIONS]) == len(bench.sent[THUMBNAIL_ANNOTATIONS])


def test_the_thumbnail_text_is_stroked_inside_its_backing() -> None:
    bench = Bench()
    bench.feedback(-45.0, 0.0, yaw=90.0)
    message = bench.last(THUMBNAIL_ANNOTATIONS)
    assert message["texts"] == []  # Studio 1.48 draws no text annotations; lines it does
    backing, glyphs = message["points"]
    xs = [p["x"] for p in backing["points"]]
    ys = [p["y"] for p in backing["points"]]
    assert glyphs["type"] == 4 and len(glyphs["points"]) % 2 == 0 and glyphs["points"]
    for point in glyphs["points"]:
        assert min(xs) <= point["x"] <= max(xs) and min(ys) <= point["y"] <= max(ys)
    assert max(xs) < 320 and max(ys) < 180 / 3
    text = "P -45.0  Y 90.0  Z ?"
    place = text_place(text, 180)
    assert len(glyphs["points"]) == 2 * len(list(text_segments(text, 0, 0, place.scale)))
    assert set(text) <= set(GLYPHS)


# -- the report's pictures ----------------------------------------------------------------------


def grey_jpeg(width: int, height: int) -> bytes:
    """A mid-grey JPEG as the recorder's thumbnails are made (PyAV's MJPEG encoder)."""
    frame = av.VideoFrame(width, height, "yuvj420p")
    for plane, value in zip(frame.planes, (128, 128, 128), strict=True):
        plane.update(bytes([value]) * plane.buffer_size)
    encoder = av.CodecContext.create("mjpeg", "w")
    encoder.width, encoder.height, encoder.pix_fmt = width, height, "yuvj420p"
    encoder.time_base = Fraction(1, 25)
    return bytes([*encoder.encode(frame), *encoder.encode(None)][0])


def rgb_at(jpeg: bytes, x: int, y: int) -> tuple[int, int, int]:
    frame = av.CodecContext.create("mjpeg", "r").decode(av.Packet(jpeg))[0]
    rgb = frame.reformat(format="rgb24")
    plane = rgb.planes[0]
    i = y * plane.line_size + x * 3
    data = bytes(plane)
    return data[i], data[i + 1], data[i + 2]


def test_the_report_pictures_show_the_overlay_of_their_moment() -> None:
    bench = Bench()
    events = []
    events += bench.frames(FEEDBACK_ID, *segments(encode_attitude(pitch_deg=-45, yaw_deg=90)))
    before = bench.time
    events += bench.frames(
        CONTROL_ID, encode_command("tracking", x=4096, y=4096, width=1600, height=1600)
    )
    picture = Thumbnail("main", bench.time + 0.5, grey_jpeg(320, 180))
    timeline = OverlayTimeline([before - 1, before, picture.time])  # the pictures' times
    for event in events:
        timeline.add(event)
    (early,) = timeline.pictures([Thumbnail("main", before, picture.jpeg)])
    (late,) = timeline.pictures([picture])
    assert early.overlay.box is None and late.overlay.box is not None  # type: ignore[attr-defined]
    assert timeline.at(before - 1) is None
    drawn = late.jpeg
    left, top, right, bottom = (round(v) for v in box_corners(late.overlay.box, 320, 180))  # type: ignore[attr-defined]
    red, green, blue = rgb_at(drawn, (left + right) // 2, top)  # the box's top edge
    assert green > 200 and red < 140 and blue < 140
    assert all(abs(c - 128) < 12 for c in rgb_at(drawn, (left + right) // 2, (top + bottom) // 2))
    place = text_place(late.overlay.text, 180)  # type: ignore[attr-defined]
    ink = [
        max(rgb_at(drawn, round(a[0]), round(a[1])))
        for a, _ in text_segments(late.overlay.text, place.left, place.top, place.scale)  # type: ignore[attr-defined]
    ]
    assert sorted(ink)[len(ink) // 2] > 200  # the glyphs are drawn white
    elsewhere = zip(rgb_at(drawn, 300, 170), rgb_at(picture.jpeg, 300, 170), strict=True)
    assert all(abs(a - b) <= 6 for a, b in elsewhere)  # the rest as it was (JPEG again)


def test_up_is_from_the_first_altitude_even_when_it_comes_after_the_first_fix() -> None:
    bench = Bench()
    bench.uav(0.0)
    bench.frames(GPS_ID, encode_gps(31.0, 118.0))
    bench.frames(ALTITUDE_ID, encode_altitude(120.0))
    bench.frames(ALTITUDE_ID, encode_altitude(125.5))
    bench.frames(GPS_ID, encode_gps(31.0, 118.0))
    bench.feedback(0.0, 0.0)
    assert transforms(bench)["uav"][2] == Vector(0.0, 0.0, pytest.approx(5.5))


_ANY_VALUE = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(2**40), 2**40),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=8),
)
_FIELDS = (
    "name", "x", "y", "width", "height", "x_pct", "y_pct", "action", "axis", "zoom",
    "pitch_deg", "yaw_deg", "motor_yaw_deg", "roll_deg", "tracking", "success", "distance_m",
    "latitude_deg", "longitude_deg", "altitude_m",
)  # fmt: skip
_TOPICS = (
    "/gimbal/command", "/gimbal/attitude", "/gimbal/ranging", "/uav/attitude", "/uav/gps",
    "/uav/altitude",
)  # fmt: skip


@pytest.mark.slow
@settings(max_examples=200, deadline=None)
@given(
    st.lists(
        st.tuples(st.sampled_from(_TOPICS), st.dictionaries(st.sampled_from(_FIELDS), _ANY_VALUE)),
        max_size=12,
    )
)
def test_any_field_values_give_valid_views_and_never_raise(
    events: list[tuple[str, dict[str, Any]]],
) -> None:
    bench = Bench()
    timeline = OverlayTimeline(1_700_000_000.0 + n + 0.5 for n in range(len(events)))
    for n, (topic, fields) in enumerate(events):
        event = Event(topic, 1_700_000_000.0 + n, "test", dict(fields))
        timeline.add(event)
        for view_topic, message in bench.views.views(event):
            VALIDATORS[view_topic].validate(json.loads(json.dumps(message, allow_nan=False)))


def _moving_gimbal(count: int, rate_hz: float = 100.0) -> list[Event]:
    """Feedback of a gimbal sweeping its pitch and yaw, and a zoom command now and then."""
    events = []
    for n in range(count):
        t = 1_700_000_000.0 + n / rate_hz
        fields = {"pitch_deg": -45 + 40 * math.sin(n / 300), "yaw_deg": (n * 0.7) % 360 - 180}
        events.append(Event("/gimbal/attitude", t, "test", fields))
        if n % 1000 == 500:
            events.append(Event("/gimbal/command", t, "test", {"name": "zoom_1x"}))
    return events


def test_the_overlay_at_each_picture_is_that_of_the_last_feedback_before_it() -> None:
    events = _moving_gimbal(3000)
    # Pictures every 2 s, one exactly at a feedback's time, one before the first feedback.
    moments = [
        events[0].time - 1,
        events[700].time,
        *(events[0].time + 0.013 + 2 * k for k in range(15)),
    ]
    timeline = OverlayTimeline(moments)
    reference = GimbalState()
    after: list[tuple[float, Any]] = []  # every feedback's overlay, as drawn in Foxglove
    for event in events:
        timeline.add(event)
        if reference.observe(event):
            after.append((event.time, overlay(reference)))
    for t in moments:
        passed = [shown for when, shown in after if when <= t]
        assert timeline.at(t) == (passed[-1] if passed else None), t
    assert timeline.at(moments[0]) is None
    with pytest.raises(KeyError):
        timeline.at(moments[1] + 0.001)  # not a picture's moment


@pytest.mark.slow
def test_the_overlays_kept_grow_with_the_pictures_not_with_the_feedback() -> None:
    pictures = [1_700_000_000.0 + 2.0 * k + 0.5 for k in range(50)]  # the first 100 s
    kept = []
    for count in (20_000, 200_000):  # 200 s and 2000 s of 100 Hz feedback
        timeline = OverlayTimeline(pictures)
        for event in _moving_gimbal(count):
            timeline.add(event)
        kept.append(timeline.kept)
        assert all(timeline.at(t) is not None for t in pictures)
    assert kept == [50, 50]  # one overlay per picture, however long the flight
