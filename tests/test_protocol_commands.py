"""Chapter 2.1: every row of the command table decodes and encodes; the examples hold."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from analyzer.protocol.codec import EncodeError, decode_command, encode_command
from analyzer.protocol.command_table import COMMANDS, CommandRow
from analyzer.protocol.fields import Field

# The document's "Examples of common functions" table, with the values it names.
SPEC_EXAMPLES = [
    ("0F 02 00 00 00 00 00 00", "forward", {}),
    ("0F 04 0C FE 00 00 00 00", "gimbal_control", {"pan_speed_dps": -5.0, "tilt_speed_dps": 0.0}),
    ("0F 04 00 00 F4 01 00 00", "gimbal_control", {"pan_speed_dps": 0.0, "tilt_speed_dps": 5.0}),
    ("0F 08 01 C2 01 00 00 00", "specified_angle", {"axis": "yaw", "yaw_deg": 45.0}),
    ("0F 08 02 3E FE 00 00 00", "specified_angle", {"axis": "pitch", "pitch_deg": -45.0}),
    ("0F 08 03 E8 03 00 00 00", "specified_angle", {"axis": "zoom", "zoom": 10.0}),
    ("0F 10 01 00 00 00 00 00", "snapshot", {"mode": "single"}),
    ("0F 11 01 00 00 00 00 00", "recording", {"action": "start"}),
]


@pytest.mark.parametrize(("hex_data", "name", "values"), SPEC_EXAMPLES)
def test_spec_examples_decode_to_the_values_they_name(
    hex_data: str, name: str, values: dict[str, object]
) -> None:
    fields, warnings = decode_command(bytes.fromhex(hex_data))
    assert warnings == []
    assert fields["name"] == name
    assert fields["s_id"] == 0x0F
    assert fields["raw"] == hex_data
    for key, value in values.items():
        assert fields[key] == value


@pytest.mark.parametrize(("hex_data", "name", "values"), SPEC_EXAMPLES)
def test_spec_examples_encode_back_byte_for_byte(
    hex_data: str, name: str, values: dict[str, object]
) -> None:
    assert encode_command(name, **values) == bytes.fromhex(hex_data)


def test_turn_left_is_negative_pan_speed() -> None:
    assert encode_command("gimbal_control", pan_speed_dps=-5) == bytes.fromhex("0F040CFE00000000")


def test_pan_80_of_the_notes() -> None:
    assert encode_command("gimbal_control", pan_speed_dps=80) == bytes.fromhex("0F04401F00000000")


def _example_value(f: Field) -> object:
    if f.labels:
        return list(f.labels.values())[-1]
    if f.boolean:
        return True
    hi = f.maximum if f.maximum is not None else 200
    hi = f.soft_maximum if f.soft_maximum is not None else hi
    lo = f.minimum if f.minimum is not None else 0
    raw = hi if f.expected is None else f.expected
    raw = min(raw, 255) if f.kind == "u8" else raw
    raw = max(raw, lo)
    return f.scale(raw)


def _cases() -> list[tuple[CommandRow, int | None, dict[str, object]]]:
    cases: list[tuple[CommandRow, int | None, dict[str, object]]] = []
    for row in COMMANDS:
        params = {f.name: _example_value(f) for f in row.params}
        if row.selector is None:
            cases.append((row, None, params))
            continue
        for key, variant in row.variants.items():
            values = dict(params)
            values.update({f.name: _example_value(f) for f in variant})
            cases.append((row, key, values))
    return cases


@pytest.mark.parametrize(
    ("row", "variant", "values"),
    _cases(),
    ids=lambda v: v.name if isinstance(v, CommandRow) else str(v) if isinstance(v, int) else "",
)
def test_every_row_round_trips(
    row: CommandRow, variant: int | None, values: dict[str, object]
) -> None:
    kwargs = dict(values)
    if variant is not None and row.selector is not None:
        kwargs[row.selector.name] = variant
    data = encode_command(row.name, s_id=row.s_id, **kwargs)
    assert len(data) == 8
    assert data[0] == row.s_id and data[1] == row.cmd
    fields, warnings = decode_command(data)
    assert warnings == []
    assert fields["name"] == row.name
    assert fields["s_id"] == row.s_id and fields["cmd"] == row.cmd
    for key, value in values.items():
        assert fields[key] == value, key
    # and decoding then re-encoding gives the same bytes
    names = {f.name for f in row.all_fields()}
    again = {k: v for k, v in fields.items() if k in names}
    assert encode_command(row.name, s_id=row.s_id, **again) == data


def test_both_components_are_in_the_table() -> None:
    gimbal = {c.cmd for c in COMMANDS if c.s_id == 0x0F}
    dual = {c.cmd for c in COMMANDS if c.s_id == 0x1F}
    assert gimbal == {0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08, 0x10, 0x11, 0x12, 0x13,
                      0x14, 0xF0}  # fmt: skip
    assert dual == {0x01, 0x02, 0x03, 0x04, 0x05, 0x07, 0x12}


def test_dual_sensor_gimbal_control() -> None:
    data = encode_command("gimbal_control", s_id=0x1F, pan_speed_dps=1.5, tilt_speed_dps=-2)
    assert data == bytes.fromhex("1F 04 96 00 38 FF 00 00")
    fields, _ = decode_command(data)
    assert fields["name"] == "gimbal_control"
    assert fields["component"] == "dual_sensor"
    assert fields["pan_speed_dps"] == 1.5 and fields["tilt_speed_dps"] == -2.0
    assert encode_command("gimbal_control", component="dual_sensor", pan_speed_dps=1.5,
                          tilt_speed_dps=-2) == data  # fmt: skip


def test_palettes_have_labels() -> None:
    fields, warnings = decode_command(bytes.fromhex("1F 02 02 00 00 00 00 00"))
    assert fields["name"] == "palette" and fields["palette"] == "iron_red" and not warnings
    assert encode_command("palette", palette="cryogenic_blue")[2] == 0x0E
    assert (
        decode_command(bytes.fromhex("1F 02 0E 00 00 00 00 00"))[0]["palette"] == "cryogenic_blue"
    )


def test_tracking_box() -> None:
    data = encode_command("tracking", x=4096, y=100, width=320, height=160)
    assert data == bytes.fromhex("0F 05 00 10 64 00 14 0A")
    fields, _ = decode_command(data)
    assert (fields["x"], fields["y"], fields["width"], fields["height"]) == (4096, 100, 320, 160)


def test_look_down_is_one_key_to_down() -> None:
    fields, _ = decode_command(bytes.fromhex("0F 07 00 00 00 00 00 00"))
    assert fields["name"] == "look_down"
    dual, _ = decode_command(bytes.fromhex("1F 07 00 00 00 00 00 00"))
    assert dual["name"] == "tracking_stop"


def test_coordinate_system_flag() -> None:
    fields, _ = decode_command(bytes.fromhex("0F 08 01 C2 01 01 00 00"))
    assert fields["coordinate_system"] == "airframe" and fields["coordinate_system_code"] == 1
    fields, _ = decode_command(bytes.fromhex("0F 08 01 C2 01 07 00 00"))
    assert fields["coordinate_system"] == "geodetic" and fields["coordinate_system_code"] == 7
    assert encode_command("specified_angle", yaw_deg=45, coordinate_system="airframe")[5] == 1


def test_snapshot_variants() -> None:
    assert encode_command("snapshot", mode="continuous", shots=5) == bytes.fromhex(
        "0F10020500000000"
    )
    fields, _ = decode_command(bytes.fromhex("0F 10 03 0A 00 00 00 00"))
    assert fields["mode"] == "time_lapse" and fields["delay_s"] == 10


def test_zoom_above_30x_is_flagged_as_model_specific() -> None:
    fields, warnings = decode_command(bytes.fromhex("0F 08 03 AC 0D 00 00 00"))  # 35.00x
    assert fields["zoom"] == 35.0
    assert warnings == ["zoom: 35.00 above 30x: only 35x models reach it"]


def test_out_of_range_is_decoded_and_flagged() -> None:
    fields, warnings = decode_command(bytes.fromhex("0F 04 11 27 00 00 00 00"))  # 100.01 deg/s
    assert fields["pan_speed_dps"] == 100.01
    assert warnings == ["pan_speed_dps: 100.01 deg/s out of range [-100.00, 100.00] deg/s"]
    fields, warnings = decode_command(bytes.fromhex("0F 08 01 11 0E 00 00 00"))  # yaw 360.1
    assert fields["yaw_deg"] == 360.1 and "out of range" in warnings[0]


def test_unknown_command_and_component() -> None:
    fields, warnings = decode_command(bytes.fromhex("0F 09 01 02 03 04 05 06"))
    assert fields["name"] == "unknown" and fields["cmd"] == 9
    assert fields["raw"] == "0F 09 01 02 03 04 05 06"
    assert warnings == ["unknown command CMD 0x09 for S_ID 0x0F"]
    fields, warnings = decode_command(bytes.fromhex("2F 04 00 00 00 00 00 00"))
    assert fields["name"] == "unknown" and "S_ID 0x2F" in warnings[0]


def test_unused_bytes_and_short_frames_are_flagged() -> None:
    _, warnings = decode_command(bytes.fromhex("0F 07 00 00 00 00 00 01"))
    assert warnings == ["bytes not used by look_down are not zero: DATA6=0x01"]
    fields, warnings = decode_command(bytes.fromhex("0F 04 0C FE"))
    assert fields["pan_speed_dps"] == -5.0 and "4 data bytes" in warnings[0]


def test_encode_errors_name_the_valid_range() -> None:
    with pytest.raises(EncodeError, match=r"pan_speed_dps: 150 out of range \[-100.00, 100.00\]"):
        encode_command("gimbal_control", pan_speed_dps=150)
    with pytest.raises(EncodeError, match="unknown command 'spin'"):
        encode_command("spin")
    with pytest.raises(EncodeError, match="unknown parameter"):
        encode_command("gimbal_control", speed=1)
    with pytest.raises(EncodeError, match="valid: black_hot"):
        encode_command("palette", palette="purple")
    with pytest.raises(EncodeError, match="give axis or one of"):
        encode_command("specified_angle")
    with pytest.raises(EncodeError, match="axis=yaw takes yaw_deg, not pitch_deg"):
        encode_command("specified_angle", yaw_deg=1, pitch_deg=2)
    with pytest.raises(EncodeError, match="mode=single takes no value, not shots"):
        encode_command("snapshot", mode="single", shots=3)
    with pytest.raises(EncodeError, match="does not exist for S_ID 0x1F"):
        encode_command("look_down", s_id=0x1F)
    # fault injection may go past the range
    assert (
        encode_command("gimbal_control", pan_speed_dps=150, check_range=False)[2:4] == b"\x98\x3a"
    )


@given(st.binary(max_size=12))
def test_decode_never_raises(data: bytes) -> None:
    fields, warnings = decode_command(data)
    assert "name" in fields and isinstance(warnings, list)
