"""The DBC export, read by cantools, decodes every frame exactly as our own decoder does."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import cantools
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from analyzer.export.dbc import CMD_SIGNALS, command_signal_name, dbc_text
from analyzer.protocol.codec import decode_command, encode_command
from analyzer.protocol.command_table import BY_CODE, COMMANDS, CommandRow
from analyzer.protocol.fields import Field
from analyzer.protocol.ids import (
    ALTITUDE_ID,
    CONTROL_ID,
    FEEDBACK_ID,
    GPS_ID,
    TEXT_END_ID,
    TEXT_ID,
    UAV_ATTITUDE_ID,
)
from analyzer.protocol.uav import STATUS_FRAMES, decode_status, encode_text
from tests.test_protocol_commands import SPEC_EXAMPLES, _cases

ROOT = Path(__file__).resolve().parent.parent
DB = cantools.database.load_string(dbc_text(), database_format="dbc", strict=True)

# NOTES.md: pan 80.00 deg/s; the chapter 3 examples carry these CAN data.
NOTES_COMMANDS = ["0F 04 40 1F 00 00 00 00", "0F 07 00 00 00 00 00 00"]
SPEC_STATUS = [
    (GPS_ID, "07 10 8D 12 87 35 68 46", {"latitude_deg": 31.1234567, "longitude_deg": 118.1234567}),
    (ALTITUDE_ID, "F6 C5 00 00 00 00 00 00", {"altitude_m": 506.78}),
]


def _our_label_and_code(f: Field, ours: dict[str, Any]) -> tuple[Any, int]:
    """A labelled field of our events: the label in ``X``, the raw number in ``X_code``."""
    return ours[f.name], int(ours[f.code_name])


def _same_field(f: Field, name: str, ours: dict[str, Any], labelled: Any, raw: Any) -> None:
    if f.labels is not None:
        label, code = _our_label_and_code(f, ours)
        assert raw == code, name
        dbc_labels = dict(f.labels)
        if f.other_label is not None:
            dbc_labels.setdefault(0, f.other_label)
        if code in dbc_labels:
            assert str(labelled) == label == dbc_labels[code], name
        else:  # a value the table does not name: cantools gives the number
            assert labelled == code, name
            assert label in (code, f.other_label) or str(label).startswith("unknown"), name
        return
    value = ours[f.name]
    assert raw == round(value * f.div / f.mul), name
    assert math.isclose(labelled, value, rel_tol=1e-12, abs_tol=1e-12), (name, labelled, value)


def assert_command_matches(data: bytes) -> dict[str, Any]:
    """cantools and decode_command agree on every value of one control frame."""
    ours, _ = decode_command(data)
    row = BY_CODE[(data[0], data[1])]
    labelled = DB.decode_message(CONTROL_ID, data)
    raw = DB.decode_message(CONTROL_ID, data, decode_choices=False, scaling=False)
    assert str(labelled["s_id"]) == ours["component"]
    cmd_signal = CMD_SIGNALS[row.s_id]
    assert str(labelled[cmd_signal]) == ours["name"]
    seen = {"s_id", cmd_signal}
    fields = list(row.params)
    if row.selector is not None:
        fields.append(row.selector)
        fields.extend(row.variants.get(row.selector.read_raw(data), ()))
    for f in fields:
        name = command_signal_name(row, f)
        seen.add(name)
        _same_field(f, name, ours, labelled[name], raw[name])
    assert set(labelled) == seen
    return dict(labelled)


def assert_status_matches(can_id: int, data: bytes) -> dict[str, Any]:
    ours, _ = decode_status(can_id, data)
    labelled = DB.decode_message(can_id, data)
    raw = DB.decode_message(can_id, data, decode_choices=False, scaling=False)
    fields = STATUS_FRAMES[can_id].layout.fields
    assert set(labelled) == {f.name for f in fields}
    for f in fields:
        _same_field(f, f.name, ours, labelled[f.name], raw[f.name])
    return dict(labelled)


def test_the_file_loads_with_every_frame_of_the_protocol(tmp_path: Path) -> None:
    path = tmp_path / "gimbal.dbc"
    cmd = [sys.executable, "-m", "analyzer", "export", "dbc", "-o", str(path)]
    subprocess.run(cmd, check=True, capture_output=True, cwd=ROOT)
    db = cantools.database.load_file(str(path), strict=True)
    ids = {m.frame_id: m for m in db.messages}
    for can_id in (CONTROL_ID, FEEDBACK_ID, GPS_ID, ALTITUDE_ID, UAV_ATTITUDE_ID):
        assert ids[can_id].is_extended_frame and ids[can_id].length == 8
    assert {TEXT_ID, TEXT_END_ID} <= set(ids)
    assert "gimbal-analyzer" in (ids[FEEDBACK_ID].comment or "")
    assert "four" in (ids[FEEDBACK_ID].comment or "")


def test_every_parameter_carries_scale_unit_range_and_labels() -> None:
    message = DB.get_message_by_frame_id(CONTROL_ID)
    pan = message.get_signal_by_name("gimbal_control_pan_speed_dps")
    assert (pan.scale, pan.unit, pan.minimum, pan.maximum) == (0.01, "deg/s", -100, 100)
    assert pan.is_signed and pan.comment
    palette = message.get_signal_by_name("ds_palette")
    assert palette.choices is not None and str(palette.choices[0x0E]) == "cryogenic_blue"
    zoom = message.get_signal_by_name("specified_angle_zoom")
    assert (zoom.minimum, zoom.maximum, zoom.unit) == (1, 35, "x")
    assert "35x" in (zoom.comment or "")
    for row in COMMANDS:
        for f in row.all_fields():
            signal = message.get_signal_by_name(command_signal_name(row, f))
            assert (signal.unit or "") == f.unit
            if f.labels is not None:
                assert signal.choices is not None
                assert {k: str(v) for k, v in signal.choices.items() if k in f.labels} == dict(
                    f.labels
                )


@pytest.mark.parametrize(("hex_data", "name", "values"), SPEC_EXAMPLES)
def test_the_vendor_examples_decode_alike(hex_data: str, name: str, values: dict[str, Any]) -> None:
    decoded = assert_command_matches(bytes.fromhex(hex_data))
    row = BY_CODE[(0x0F, bytes.fromhex(hex_data)[1])]
    assert str(decoded["gimbal_cmd"]) == name
    for key, value in values.items():
        f = next(f for f in row.all_fields() if f.name == key)
        assert decoded[command_signal_name(row, f)] == value


@pytest.mark.parametrize("hex_data", NOTES_COMMANDS)
def test_the_notes_vectors_decode_alike(hex_data: str) -> None:
    assert_command_matches(bytes.fromhex(hex_data))


@pytest.mark.parametrize(("can_id", "hex_data", "values"), SPEC_STATUS)
def test_the_uav_examples_decode_alike(can_id: int, hex_data: str, values: dict[str, Any]) -> None:
    decoded = assert_status_matches(can_id, bytes.fromhex(hex_data))
    for key, value in values.items():
        assert math.isclose(decoded[key], value, rel_tol=1e-12)


@pytest.mark.parametrize(
    ("row", "variant", "values"),
    _cases(),
    ids=lambda v: v.name if isinstance(v, CommandRow) else str(v) if isinstance(v, int) else "",
)
def test_every_row_decodes_alike_and_encodes_back(
    row: CommandRow, variant: int | None, values: dict[str, Any]
) -> None:
    kwargs = dict(values)
    if variant is not None and row.selector is not None:
        kwargs[row.selector.name] = variant
    data = encode_command(row.name, s_id=row.s_id, **kwargs)
    decoded = assert_command_matches(data)
    assert DB.encode_message(CONTROL_ID, decoded) == data


def test_text_frames_carry_the_text() -> None:
    text = "".join(
        "".join(chr(int(v)) for _, v in sorted(DB.decode_message(cid, data).items()) if int(v))
        for cid, data in encode_text("LOW BATTERY, RTH")
    )
    assert text == "LOW BATTERY, RTH"


def _command_frame(draw: st.DrawFn) -> bytes:
    row = draw(st.sampled_from(COMMANDS))
    data = bytearray(draw(st.binary(min_size=8, max_size=8)))
    data[0], data[1] = row.s_id, row.cmd
    if row.selector is not None:
        data[row.selector.offset] = draw(st.sampled_from(sorted(row.variants)))
    labelled = [f for f in row.all_fields() if f.labels is not None and f is not row.selector]
    for f in labelled:
        if draw(st.booleans()):
            data[f.offset] = draw(st.sampled_from(sorted(f.labels or {})))
    return bytes(data)


@settings(max_examples=300, deadline=None)
@given(st.composite(_command_frame)())
def test_random_valid_commands_decode_alike(data: bytes) -> None:
    assert_command_matches(data)


@settings(max_examples=100, deadline=None)
@given(st.sampled_from(sorted(STATUS_FRAMES)), st.binary(min_size=8, max_size=8))
def test_random_uav_frames_decode_alike(can_id: int, data: bytes) -> None:
    assert_status_matches(can_id, data)


def test_export_command_writes_checks_and_refuses_to_overwrite(tmp_path: Path) -> None:
    out = tmp_path / "gimbal.dbc"
    cmd = [sys.executable, "-c", "import sys; from analyzer.cli import main; sys.exit(main())"]
    run = subprocess.run(
        [*cmd, "export", "dbc", "-o", str(out)], capture_output=True, text=True, encoding="utf-8"
    )
    assert run.returncode == 0, run.stderr
    assert out.read_text(encoding="utf-8") == dbc_text()
    again = subprocess.run(
        [*cmd, "export", "dbc", "-o", str(out)], capture_output=True, text=True, encoding="utf-8"
    )
    assert again.returncode == 2 and "--force" in again.stderr
    out.write_text("stale", encoding="utf-8")
    check = [*cmd, "export", "dbc", "-o", str(out), "--check"]
    stale = subprocess.run(check, capture_output=True, text=True, encoding="utf-8")
    assert stale.returncode == 1 and "out of date" in stale.stdout
    forced = [*cmd, "export", "dbc", "-o", str(out), "--force"]
    assert subprocess.run(forced, capture_output=True, text=True, encoding="utf-8").returncode == 0
    assert subprocess.run(check, capture_output=True, text=True, encoding="utf-8").returncode == 0
    assert list(tmp_path.iterdir()) == [out]  # no temporary file left behind
