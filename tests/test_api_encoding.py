"""The Python API's encoders: the document's own examples built by name and unit, and errors
that name the parameter, the value and the range."""

from __future__ import annotations

import can
import pytest

from analyzer import (
    COMMANDS,
    can_message,
    encode,
    status_message,
    tcp_frame,
    text_messages,
)
from analyzer.protocol.codec import decode_command
from analyzer.protocol.command_table import COMMANDS as TABLE
from tests.test_protocol_commands import SPEC_EXAMPLES

# Chapter 2.1.1, "Examples of common functions": every CANDATA line, with the function and
# description the document gives it, as an integrator writes it with names and units.
DOCUMENT_LINES = [
    ("Forward", "0F 02 00 00 00 00 00 00", "forward", {}),
    ("Turn left 5°/Sec", "0F 04 0C FE 00 00 00 00", "gimbal_control", {"pan_speed_dps": -5}),
    ("Pull up 5°/Sec", "0F 04 00 00 F4 01 00 00", "gimbal_control", {"tilt_speed_dps": 5}),
    ("Yaw: 45", "0F 08 01 C2 01 00 00 00", "specified_angle", {"axis": "yaw", "yaw_deg": 45}),
    ("Pitch: -45", "0F 08 02 3E FE 00 00 00", "specified_angle", {"pitch_deg": -45}),
    ("Zoom: 10", "0F 08 03 E8 03 00 00 00", "specified_angle", {"zoom": 10}),
    ("Single shot", "0F 10 01 00 00 00 00 00", "snapshot", {"mode": "single"}),
    ("Recording", "0F 11 01 00 00 00 00 00", "recording", {"action": "start"}),
]


def test_the_lines_above_are_every_candata_line_of_chapter_2_1_1() -> None:
    assert [line[1] for line in DOCUMENT_LINES] == [example[0] for example in SPEC_EXAMPLES]


@pytest.mark.parametrize(("what", "candata", "name", "params"), DOCUMENT_LINES)
def test_every_candata_line_of_the_document_is_built_by_name_and_unit(
    what: str, candata: str, name: str, params: dict[str, float | str]
) -> None:
    assert encode(name, **params) == bytes.fromhex(candata), what
    message = can_message(name, **params)
    assert message.arbitration_id == 0x00000F01 and message.is_extended_id
    assert message.dlc == 8 and bytes(message.data) == bytes.fromhex(candata)


def test_one_key_to_down_is_the_tcp_frame_of_chapter_3_as_corrected() -> None:
    # NOTES.md: the document's example has one zero byte too many; this one's CRC checks.
    frame = "EB 90 0A 00 00 00 00 00 00 00 00 00 40 88 0F 07 00 00 00 00 00 00 68 5E"
    assert tcp_frame("look_down") == bytes.fromhex(frame)
    # and the second frame the notes checked: pan 80.00 deg/s
    pan = "EB 90 0A 00 00 00 00 00 00 00 00 00 40 88 0F 04 40 1F 00 00 00 00 C0 5C"
    assert tcp_frame("gimbal_control", pan_speed_dps=80) == bytes.fromhex(pan)


def test_the_uav_status_examples_of_chapter_2_3() -> None:
    gps = status_message("gps", latitude_deg=31.1234567, longitude_deg=118.1234567)
    assert (gps.arbitration_id, bytes(gps.data)) == (0xFF15, bytes.fromhex("07108D1287356846"))
    altitude = status_message("altitude", altitude_m=506.78)
    assert (altitude.arbitration_id, bytes(altitude.data)) == (
        0xFF16,
        bytes.fromhex("F6C5") + bytes(6),
    )
    attitude = status_message("attitude", pitch_deg=10, roll_deg=-10, yaw_deg=180)
    assert attitude.arbitration_id == 0xFF13
    assert bytes(attitude.data) == bytes.fromhex("E8 03 18 FC 50 46 00 00")
    assert all(m.is_extended_id and isinstance(m, can.Message) for m in (gps, altitude, attitude))
    short = status_message("text", text="RTL")
    assert (short.arbitration_id, bytes(short.data)) == (0x02008202, b"RTL" + bytes(5))
    frames = text_messages("Low battery: return to home")
    assert [m.arbitration_id for m in frames] == [0x02008201] * 3 + [0x02008202]
    assert b"".join(bytes(m.data) for m in frames).rstrip(b"\0") == b"Low battery: return to home"


def test_the_dual_sensor_commands_need_their_component() -> None:
    assert encode("gimbal_control", component="dual_sensor", pan_speed_dps=1.5) == bytes.fromhex(
        "1F 04 96 00 00 00 00 00"
    )
    assert encode("palette", component="dual_sensor", palette="lava")[:3] == bytes.fromhex("1F0204")
    with pytest.raises(
        ValueError, match=r"palette does not exist for component gimbal .*valid: dual_sensor"
    ):
        encode("palette", palette="lava")


@pytest.mark.parametrize(
    ("name", "params", "message"),
    [
        # out of the document's range: the parameter, the value and the range
        ("gimbal_control", {"pan_speed_dps": 150},
         r"^gimbal_control: pan_speed_dps: 150 out of range \[-100.00, 100.00\] deg/s$"),
        ("specified_angle", {"pitch_deg": -120},
         r"^specified_angle: pitch_deg: -120 out of range \[-100.0, 60.0\] deg$"),
        ("specified_angle", {"zoom": 0.5}, r"zoom: 0.5 out of range \[1.00, 35.00\] x$"),
        ("tracking", {"x": 9000, "y": 0, "width": 16, "height": 16},
         r"^tracking: x: 9000 out of range \[0, 8191\]$"),
        ("tap_zoom", {"x_pct": 100.5, "y_pct": 0}, r"x_pct: 100.5 out of range \[-100.00, 100.00\] %"),
        # a label the table does not know: the valid ones
        ("zoom", {"action": "faster"},
         r"^zoom: action: unknown value 'faster'; valid: zoom_in, zoom_out, stop, zoom_1x"),
        ("specified_angle", {"axis": "roll"}, r"axis: unknown value 'roll'; valid: yaw, pitch, zoom"),
        # unknown command or parameter, and a missing one with what it takes
        ("spin", {}, r"^unknown command 'spin'; valid: tap_zoom, forward"),
        ("gimbal_control", {"pan_speed": 5},
         r"^gimbal_control: unknown parameter\(s\) pan_speed; valid: pan_speed_dps, tilt_speed_dps$"),
        ("gimbal_control", {"check_range": 0}, r"unknown parameter\(s\) check_range"),
        ("tap_zoom", {"x_pct": 10}, r"^tap_zoom: missing parameter y_pct \(range \[-100.00, 100.00\] %\)$"),
        ("tracking", {"x": 1, "y": 2, "width": 320},
         r"^tracking: missing parameter height \(range \[0, 4080\] px\)$"),
        ("recording", {}, r"^recording: missing parameter action \(one of start, stop\)$"),
        ("snapshot", {"mode": "continuous"}, r"^snapshot: missing parameter shots \(range \[0, 255\]\)$"),
        ("gimbal_control", {"tilt_speed_dps": "fast"}, r"tilt_speed_dps: 'fast' is not a number"),
    ],
)  # fmt: skip
def test_errors_name_the_parameter_the_value_and_the_range(
    name: str, params: dict[str, float | str], message: str
) -> None:
    with pytest.raises(ValueError, match=message):
        encode(name, **params)
    with pytest.raises(ValueError, match=message):
        can_message(name, **params)
    with pytest.raises(ValueError, match=message):
        tcp_frame(name, **params)


@pytest.mark.parametrize(
    ("name", "values", "message"),
    [
        ("gps", {"latitude_deg": 91, "longitude_deg": 0},
         r"^gps: latitude_deg: 91 out of range \[-90.0000000, 90.0000000\] deg$"),
        ("gps", {"latitude_deg": 1}, r"^gps: missing parameter longitude_deg \(range \[-180.0000000, 180.0000000\] deg\)$"),
        ("altitude", {"altitude_m": 1, "speed": 2}, r"^altitude: unknown parameter\(s\) speed; valid: altitude_m$"),
        ("battery", {}, r"^unknown status message 'battery'; valid: gps, altitude, attitude, text$"),
        ("text", {"text": "Battery low"}, r"needs 2 frames of 8 bytes; text_messages\(text\) gives them all"),
        ("text", {"text": "Höhe"}, r"'ö' is not ASCII"),
    ],
)  # fmt: skip
def test_status_message_errors(name: str, values: dict[str, float | str], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        status_message(name, **values)


def test_commands_lists_every_row_of_the_table_with_units_and_ranges() -> None:
    assert [(c.s_id, c.cmd, c.name) for c in COMMANDS] == [(r.s_id, r.cmd, r.name) for r in TABLE]
    angle = next(c for c in COMMANDS if c.name == "specified_angle")
    yaw = next(p for p in angle.parameters if p.name == "yaw_deg")
    assert (yaw.unit, yaw.minimum, yaw.maximum, yaw.when) == ("deg", 0.0, 360.0, ("axis", "yaw"))
    zoom = next(p for p in angle.parameters if p.name == "zoom")
    assert (zoom.maximum, zoom.note) == (35.0, "above 30x: only 35x models reach it")
    frame = next(p for p in angle.parameters if p.name == "coordinate_system")
    assert (frame.choices, frame.default, frame.required) == (
        ("airframe", "geodetic"),
        "geodetic",
        False,
    )
    palette = next(c for c in COMMANDS if c.name == "palette")
    assert palette.component == "dual_sensor" and len(palette.parameters[0].choices) == 15


@pytest.mark.parametrize("command", COMMANDS, ids=lambda c: f"{c.component}.{c.name}")
def test_every_command_encodes_at_the_ends_of_its_ranges_and_fails_past_them(
    command: object,
) -> None:
    """What COMMANDS says is what encode accepts: each number at its minimum and maximum
    (every required parameter given), each choice, and a step past either end refused."""
    from analyzer.api.commands import Command

    assert isinstance(command, Command)
    variants = {p.when for p in command.parameters if p.when is not None} or {None}
    for when in variants:
        given = [p for p in command.parameters if p.when in (None, when)]
        base: dict[str, float | str] = {}
        if when is not None:
            base[when[0]] = when[1]
        for p in given:
            if p.required and p.name not in base:
                base[p.name] = p.choices[0] if p.choices else (p.minimum or 0.0)
        for p in given:
            if when is not None and p.name == when[0]:
                continue  # the selector: its value picks the parameters given
            values = p.choices or (p.minimum, p.maximum)
            for value in values:
                assert value is not None
                data = encode(command.name, command.component, **{**base, p.name: value})
                fields, warnings = decode_command(data)
                assert fields["name"] == command.name and fields[p.name] == value
                assert warnings == [] or p.note
            if not p.choices:
                assert p.minimum is not None and p.maximum is not None and p.resolution
                for past in (p.minimum - p.resolution, p.maximum + p.resolution):
                    with pytest.raises(ValueError, match=rf"{p.name}: .* out of range"):
                        encode(command.name, command.component, **{**base, p.name: past})
