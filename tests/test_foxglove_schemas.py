"""Every schema stays inside Foxglove's JSON Schema subset; every message matches its schema."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import jsonschema
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mcap.reader import make_reader

from analyzer.cli import main
from analyzer.mcapio.channels import CAN_FRAME_SCHEMA, STREAM_BYTES_SCHEMA, permissive_schema
from analyzer.mcapio.foxglove import VIEW_SCHEMAS, FoxgloveViews
from analyzer.mcapio.schema_subset import foxglove_problems
from analyzer.protocol.crc import crc_bytes
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.feedback import LAYOUTS, segments
from analyzer.protocol.framing import wrap_control
from analyzer.protocol.ids import CONTROL_ID, FEEDBACK_ID, HEADER
from analyzer.protocol.schema import topic_schemas
from analyzer.protocol.types import TO_IDU, TOPIC_COMMAND, CanFrame, Event, StreamChunk

ROOT = Path(__file__).resolve().parent.parent
SCHEMAS = topic_schemas()
VALIDATORS = {topic: jsonschema.Draft202012Validator(schema) for topic, schema in SCHEMAS.items()}
VIEW_VALIDATORS = {
    topic: jsonschema.Draft202012Validator(schema) for topic, (_, schema) in VIEW_SCHEMAS.items()
}


# -- the checker follows Foxglove's parseJsonSchema -----------------------------------------


def obj(**properties: Any) -> dict[str, Any]:
    return {"type": "object", "properties": properties}


@pytest.mark.parametrize(
    "schema",
    [
        obj(a={"type": "boolean"}, b={"type": "string"}, c={"type": "number"}),
        obj(d={"type": "integer", "minimum": 0}, e={"type": "string", "enum": ["x"]}),
        obj(f={"type": "string", "contentEncoding": "base64"}),
        obj(g=obj(h={"type": "number"}), i={"type": "array", "items": obj(j={"type": "string"})}),
        obj(k={"type": "array", "items": {"type": "integer"}}),
        obj(level={"oneOf": [{"title": "INFO", "const": 2}, {"title": "WARN", "const": 3}]}),
        obj(p={"type": "string", "pattern": "^(a|b|unknown_0x[0-9a-f]{2})$"}),
        obj(),
    ],
)
def test_foxglove_reads(schema: dict[str, Any]) -> None:
    assert foxglove_problems(schema) == []


@pytest.mark.parametrize(
    ("schema", "complaint"),
    [
        (obj(a={"type": ["string", "integer"]}), "unsupported type ['string', 'integer']"),
        (obj(a={"type": ["number", "null"]}), "unsupported type"),
        (obj(a={"type": "null"}), "unsupported type 'null'"),
        (obj(a={"enum": ["x", "y"]}), "unsupported type None"),
        (obj(a={"oneOf": [{"const": "x", "title": "X"}]}), "must have number values"),
        (obj(a={"oneOf": [{"const": True, "title": "X"}]}), "must have number values"),
        (obj(a={"oneOf": [{"type": "string"}, {"type": "integer"}]}), "number values"),
        (obj(a={"type": "string", "contentEncoding": "base16"}), "contentEncoding"),
        (obj(a={"type": "array", "items": {"type": "array"}}), "array items"),
        (obj(a={"type": "array", "items": {"type": ["string", "null"]}}), "array items"),
        (obj(a={"type": "array"}), "'items'"),
        (obj(a={"type": "array", "items": {"type": "string", "contentEncoding": "base64"}}), ""),
        (obj(a=obj(b={"type": ["number", "null"]})), "a.b: unsupported type"),
        (obj(a={"type": "object"}), "'properties'"),
        ({"type": "array", "items": {"type": "string"}}, 'expected "type": "object"'),
    ],
)
def test_foxglove_refuses(schema: dict[str, Any], complaint: str) -> None:
    problems = foxglove_problems(schema)
    assert problems and complaint in problems[0], problems


# -- every schema we generate or ship ----------------------------------------------------------


def test_every_generated_schema_is_in_the_foxglove_subset() -> None:
    generated: dict[str, Any] = {
        **SCHEMAS,
        "/can/frames": CAN_FRAME_SCHEMA,
        "/stream/bytes": STREAM_BYTES_SCHEMA,
        "/can/other": permissive_schema("/can/other"),
        **{topic: schema for topic, (_, schema) in VIEW_SCHEMAS.items()},
    }
    for topic, schema in generated.items():
        assert foxglove_problems(schema, topic) == [], topic
        jsonschema.Draft202012Validator.check_schema(schema)
    files = sorted((ROOT / "schemas").glob("*.schema.json"))
    assert len(files) == len(SCHEMAS)
    for path in files:
        assert foxglove_problems(json.loads(path.read_text(encoding="utf-8")), path.name) == [], (
            path.name
        )


def test_schemas_check_refuses_a_schema_foxglove_would_drop(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["schemas", str(tmp_path)]) == 0
    assert main(["schemas", "--check", str(tmp_path)]) == 0
    assert "subset Foxglove reads" in capsys.readouterr().out
    path = tmp_path / "gimbal.command.schema.json"
    schema = json.loads(path.read_text(encoding="utf-8"))
    schema["properties"]["palette"]["type"] = ["string", "integer"]  # the old, refused form
    path.write_text(json.dumps(schema), encoding="utf-8")
    assert main(["schemas", "--check", str(tmp_path)]) == 1
    out = capsys.readouterr().out
    assert "gimbal.command.schema.json: palette: unsupported type ['string', 'integer']" in out


def _recorded_schemas(path: Path) -> dict[str, Any]:
    with path.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    out: dict[str, Any] = {}
    for channel in summary.channels.values():
        schema = summary.schemas[channel.schema_id]
        assert schema.encoding == "jsonschema" and channel.message_encoding == "json"
        out[channel.topic] = json.loads(schema.data)
    return out


@pytest.mark.parametrize("sample", ["flight-candump.log", "idu-tcp.pcap", "uart-dump.bin"])
def test_schemas_written_into_recordings_are_in_the_subset(
    sample: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "sample.mcap"
    assert main(["convert", str(ROOT / "samples" / sample), "-o", str(out), "-q"]) == 0
    recorded = _recorded_schemas(out)
    assert recorded
    for topic, schema in recorded.items():
        assert foxglove_problems(schema, topic) == [], topic


# -- every decoded message validates against its own channel's schema ------------------------


def check(events: list[Event]) -> None:
    views = FoxgloveViews()
    for event in events:
        message = json.loads(json.dumps(event.to_dict()))
        VALIDATORS[event.topic].validate(message)
        for view_topic, view in views.views(event):
            VIEW_VALIDATORS[view_topic].validate(json.loads(json.dumps(view)))


def test_unknown_palette_is_a_label_with_its_code() -> None:
    (event,) = ProtocolDecoder().feed_can(
        CanFrame(1.0, CONTROL_ID, bytes.fromhex("1F027F0000000000"))
    )
    assert event.fields["palette"] == "unknown_0x7f" and event.fields["palette_code"] == 0x7F
    assert "palette: unknown value 127 (0x7F)" in event.warnings
    check([event])


def test_attitude_labels_and_codes() -> None:
    from analyzer.protocol.feedback import encode_attitude

    message = encode_attitude(
        pitch_deg=1, yaw_deg=2, gimbal_type=9, control_mode=1, check_range=False
    )
    frames = [CanFrame(1.0, FEEDBACK_ID, part) for part in segments(message)]
    decoder = ProtocolDecoder()
    events = [e for f in frames for e in decoder.feed_can(f)]
    (event,) = events
    assert event.fields["gimbal_type"] == "unknown_0x09" and event.fields["gimbal_type_code"] == 9
    assert event.fields["control_mode"] == "full_lock" and event.fields["control_mode_code"] == 1
    assert not any(k.endswith("_name") for k in event.fields)
    check(events)


FAST = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@FAST
@given(st.lists(st.binary(min_size=0, max_size=8), min_size=1, max_size=4))
def test_any_command_frame_gives_valid_events(frames: list[bytes]) -> None:
    decoder = ProtocolDecoder()
    events: list[Event] = []
    for i, data in enumerate(frames):
        events += decoder.feed_can(CanFrame(1.0 + i, CONTROL_ID, data))
    events += decoder.close()
    assert any(e.topic == TOPIC_COMMAND for e in events)
    check(events)


@FAST
@given(st.binary(min_size=8, max_size=8), st.sampled_from(["0F", "1F"]), st.integers(0, 255))
def test_any_command_over_tcp_gives_valid_events(data: bytes, s_id: str, cmd: int) -> None:
    can_data = bytes.fromhex(s_id) + bytes([cmd]) + data[2:]
    decoder = ProtocolDecoder()
    events = decoder.feed_stream(StreamChunk(1.0, wrap_control(can_data), "tcp", TO_IDU))
    events += decoder.close()
    assert [e.topic for e in events] == [TOPIC_COMMAND]
    check(events)


@FAST
@given(st.sampled_from(sorted(LAYOUTS)), st.binary(min_size=32, max_size=32))
def test_any_feedback_payload_gives_valid_events(length_byte: int, payload: bytes) -> None:
    # A well-framed message (header, length byte, CRC) around arbitrary content, so that
    # every field takes arbitrary values, including labels the document does not know.
    layout = LAYOUTS[length_byte]
    message = bytearray(payload)
    message[0:2] = HEADER
    message[2] = length_byte
    message[layout.crc_offset : layout.crc_offset + 2] = crc_bytes(message[: layout.crc_offset])
    decoder = ProtocolDecoder()
    events: list[Event] = []
    for i, part in enumerate(segments(bytes(message))):
        events += decoder.feed_can(CanFrame(1.0 + i / 100, FEEDBACK_ID, part))
    events += decoder.close()
    assert [e.topic for e in events] == [layout.topic]
    check(events)


@pytest.mark.slow
@FAST
@given(st.lists(st.tuples(st.sampled_from([FEEDBACK_ID, CONTROL_ID]), st.binary(max_size=8))))
def test_any_feedback_frames_give_valid_events(frames: list[tuple[int, bytes]]) -> None:
    decoder = ProtocolDecoder()
    events: list[Event] = []
    for i, (can_id, data) in enumerate(frames):
        events += decoder.feed_can(CanFrame(1.0 + i / 100, can_id, data))
    events += decoder.close()
    check(events)
