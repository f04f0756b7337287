"""JSON Schemas of every topic, generated from the protocol tables so they cannot drift."""

from __future__ import annotations

from typing import Any

from analyzer.protocol.command_table import COMMAND_NAMES, COMMANDS
from analyzer.protocol.feedback import ATTITUDE, RANGING
from analyzer.protocol.fields import Field
from analyzer.protocol.ids import COMPONENT_NAMES
from analyzer.protocol.types import (
    DIAGNOSTIC_KINDS,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    TOPIC_UAV_TEXT,
    TOPICS,
)
from analyzer.protocol.uav import STATUS_FRAMES

SCHEMA_DIALECT = "https://json-schema.org/draft/2020-12/schema"

_TRANSPORT = {
    "direction": {
        "type": "string",
        "enum": ["gs_to_idu", "idu_to_gs", ""],
        "description": "TCP/UART direction: ground station -> IDU or IDU -> ground station",
    },
    "transport": {
        "type": "string",
        "description": "'stream' when the event came from a TCP/UART frame",
    },
    "crc_set": {
        "type": "boolean",
        "description": "type 0x0B frames: false when the CRC was '00 00' (not set)",
    },
}


def _envelope(topic: str, title: str, description: str) -> dict[str, Any]:
    return {
        "$schema": SCHEMA_DIALECT,
        "title": title,
        "description": description,
        "type": "object",
        "properties": {
            "topic": {"type": "string", "const": topic},
            "time": {
                "type": "number",
                "description": "seconds (Unix time) of the frame that completed the event",
            },
            "source": {
                "type": "string",
                "description": "CAN channel or stream the event came from",
            },
            "warnings": {
                "type": "array",
                "items": {"type": "string"},
                "description": "doubts about the values (out of range, unused bytes set, ...)",
            },
            "raw": {
                "type": "string",
                "description": "the bytes the event was decoded from, hex (the 8 CAN bytes, the "
                "32-byte feedback message or the stream frame)",
            },
            **_TRANSPORT,
        },
        "required": ["topic", "time", "source", "warnings"],
    }


def _add_fields(schema: dict[str, Any], fields: tuple[Field, ...], *, required: bool) -> None:
    props = schema["properties"]
    for f in fields:
        new = f.json_schema()
        old = props.get(f.name)
        if old is None:
            props[f.name] = new
        elif "enum" in old and "enum" in new:
            # The same name with different label sets (e.g. ``action``): allow all.
            old["enum"] = list(dict.fromkeys([*old["enum"], *new["enum"]]))
        if f.labels is not None:
            if f.label_as:
                props[f.name] = {"type": "integer", "description": f"{f.description} (raw)"}
                props[f.label_as] = {
                    "type": "string",
                    "description": f"{f.description}: "
                    + ", ".join(f"{k} = {v}" for k, v in f.labels.items())
                    + ", or 'unknown'",
                }
            else:
                props[f.name + "_raw"] = {"type": "integer", "description": f"{f.name} as a number"}
        if required:
            schema["required"].append(f.name)


def command_schema() -> dict[str, Any]:
    schema = _envelope(
        TOPIC_COMMAND,
        "gimbal command",
        "A command of chapter 2.1 (CAN ID 0x00000F01 or a TCP/UART 0x0A frame).",
    )
    props = schema["properties"]
    props["s_id"] = {
        "type": "integer",
        "description": "component byte: 0x0F gimbal, 0x1F dual-sensor camera",
    }
    props["cmd"] = {"type": "integer", "description": "command byte"}
    props["name"] = {
        "type": "string",
        "enum": [*COMMAND_NAMES, "unknown"],
        "description": "command name from the command table",
    }
    props["component"] = {"type": "string", "enum": [*COMPONENT_NAMES.values(), "unknown"]}
    props["raw"] = {"type": "string", "description": "the 8 CAN data bytes in hex"}
    schema["required"] += ["s_id", "cmd", "name", "raw"]
    for row in COMMANDS:
        _add_fields(schema, row.all_fields(), required=False)
    return schema


def topic_schemas() -> dict[str, dict[str, Any]]:
    """Topic -> JSON Schema of its events."""
    out: dict[str, dict[str, Any]] = {TOPIC_COMMAND: command_schema()}
    for layout, what in (
        (ATTITUDE, "Gimbal attitude feedback (length byte 0x0C)."),
        (RANGING, "Laser ranging feedback (length byte 0x10)."),
    ):
        schema = _envelope(layout.topic, f"gimbal {layout.name}", what)
        _add_fields(schema, layout.layout.fields, required=True)
        out[layout.topic] = schema
    for status in STATUS_FRAMES.values():
        schema = _envelope(
            status.topic,
            f"UAV {status.name}",
            f"{status.description} (CAN ID 0x{status.can_id:08X}).",
        )
        _add_fields(schema, status.layout.fields, required=True)
        out[status.topic] = schema
    text = _envelope(
        TOPIC_UAV_TEXT,
        "UAV text message",
        "ASCII text reassembled from CAN IDs 0x02008201 / 0x02008202.",
    )
    text["properties"]["text"] = {"type": "string", "description": "the message"}
    text["properties"]["frames"] = {"type": "integer", "description": "CAN frames it took"}
    text["properties"]["start_time"] = {"type": "number", "description": "time of its first frame"}
    text["required"].append("text")
    out[TOPIC_UAV_TEXT] = text
    diag = _envelope(
        TOPIC_DIAGNOSTICS,
        "diagnostic",
        "Something on the wire that is not a valid message, with its raw bytes.",
    )
    diag["properties"].update(
        {
            "kind": {"type": "string", "enum": list(DIAGNOSTIC_KINDS)},
            "detail": {"type": "string", "description": "what is wrong, in words"},
            "raw": {"type": "string", "description": "the bytes concerned, hex"},
            "byte_count": {"type": "integer", "description": "how many bytes it accounts for"},
            "segments": {"type": "integer", "description": "feedback segments concerned"},
            "can_id": {"type": "integer"},
        }
    )
    diag["required"] += ["kind", "detail", "raw"]
    out[TOPIC_DIAGNOSTICS] = diag
    assert set(out) == set(TOPICS)
    return out


def schema_filename(topic: str) -> str:
    """'/gimbal/command' -> 'gimbal.command.schema.json'."""
    return topic.strip("/").replace("/", ".") + ".schema.json"
