"""JSON Schemas of every topic, generated from the protocol tables so they cannot drift."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from analyzer.protocol.ardupilot_fields import MOUNT_FIELDS, TARGET_ENUMS, TARGET_FIELDS
from analyzer.protocol.bus_state import BUS_STATES, count_key
from analyzer.protocol.can_error import CLASS_NAMES, UNKNOWN_CLASS, UNSPECIFIED
from analyzer.protocol.check_fields import (
    FIGURES,
    REQUIRED_FIELDS,
    STEP_FIELDS,
    STEP_NAMES,
    STEP_VERDICTS,
)
from analyzer.protocol.command_table import COMMAND_NAMES, COMMANDS
from analyzer.protocol.feedback import ATTITUDE, RANGING
from analyzer.protocol.fields import Field, label_pattern
from analyzer.protocol.ids import COMPONENT_NAMES
from analyzer.protocol.response_fields import ALL_VERDICTS, CHECKS, FIELD_ENUMS, OPTIONAL_FIELDS
from analyzer.protocol.types import (
    DIAGNOSTIC_KINDS,
    TOPIC_ANALYSIS_RESPONSE,
    TOPIC_ARDUPILOT_MOUNT,
    TOPIC_ARDUPILOT_TARGETS,
    TOPIC_CAN_BUS_STATE,
    TOPIC_CHECK_STEPS,
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


def _add_described(
    schema: dict[str, Any],
    fields: Mapping[str, tuple[str, str]],
    enums: Mapping[str, Sequence[str]] | None = None,
) -> None:
    """Add the properties of a table of name -> (JSON type, description), with the values
    ``enums`` allows for each it names."""
    props = schema["properties"]
    for name, (kind, description) in fields.items():
        props[name] = {"type": kind, "description": description}
        if enums is not None and name in enums:
            props[name]["enum"] = list(enums[name])


def _add_fields(schema: dict[str, Any], fields: tuple[Field, ...], *, required: bool) -> None:
    """Add the properties of ``fields``; a labelled ``X`` is followed by its number ``X_code``."""
    props = schema["properties"]
    labelled: dict[str, list[Field]] = {}
    for f in fields:
        if f.name not in props:
            props[f.name] = f.json_schema()
            if required:
                schema["required"].append(f.name)
        if f.labels is None:
            continue
        same = labelled.setdefault(f.name, [])
        same.append(f)
        if len(same) > 1:
            # The same name with different label sets (e.g. ``action``) accepts all of them.
            props[f.name]["pattern"] = label_pattern(same)
            props[f.name]["description"] = (
                f"{f.description} (a label; the number is in {f.code_name})"
            )
        props[f.code_name] = {
            "type": "integer",
            "minimum": 0,
            "maximum": 2 ** (8 * max(g.size for g in same)) - 1,
            "description": f"{f.name} as the raw number on the wire",
        }
        if required and len(same) == 1:
            schema["required"].append(f.code_name)


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
    _add_fields(schema, tuple(f for row in COMMANDS for f in row.all_fields()), required=False)
    return schema


def response_schema() -> dict[str, Any]:
    """Findings of the response analysis: did the gimbal do what a command asked?"""
    schema = _envelope(
        TOPIC_ANALYSIS_RESPONSE,
        "response finding",
        "A command compared with the attitude feedback that followed it (or a finding on "
        "the feedback itself); 'time' is the command's time.",
    )
    props = schema["properties"]
    props.update(
        {
            "command": {
                "type": "string",
                "description": "the command's name, or 'feedback' for feedback health",
            },
            "check": {"type": "string", "enum": list(CHECKS), "description": "what was checked"},
            "verdict": {
                "type": "string",
                "enum": list(ALL_VERDICTS),
                "description": "of a command: obeyed, partial, not_obeyed, or unknown when the "
                "feedback does not allow a judgement; of the feedback itself (command "
                "'feedback'): its health, healthy, degraded, lost, or unknown when the input "
                "holds no feedback at all",
            },
            "detail": {"type": "string", "description": "the finding in one sentence"},
        }
    )
    _add_described(schema, OPTIONAL_FIELDS, FIELD_ENUMS)
    schema["required"] += ["command", "check", "verdict", "detail"]
    return schema


def check_steps_schema() -> dict[str, Any]:
    """Steps of the bench check (`gimbal-analyzer check`): verdict and measured figures."""
    schema = _envelope(
        TOPIC_CHECK_STEPS,
        "bench check step",
        "One step of `gimbal-analyzer check`, judged by the response analysis and the "
        "figures measured from the feedback; 'time' is when the step was decided.",
    )
    _add_described(
        schema, {**STEP_FIELDS, **FIGURES}, {"step": STEP_NAMES, "verdict": STEP_VERDICTS}
    )
    schema["properties"]["findings"]["items"] = {"type": "string"}
    schema["required"] += list(REQUIRED_FIELDS)
    return schema


_NAMES = {"type": "array", "items": {"type": "string"}}
_COUNTER = {"type": "integer", "minimum": 0, "maximum": 255}
_BUS_STATE = {"type": "string", "enum": list(BUS_STATES)}
# Fields of a bus_error diagnostic (a SocketCAN error frame, linux/can/error.h); those
# the frame does not tell (no counters, no protocol violation) are left out.
ERROR_FRAME_FIELDS: dict[str, Any] = {
    "error": {
        "type": "string",
        "description": "bus_error: the error frame as candump -e explains it",
    },
    "classes": {**_NAMES, "description": "bus_error: error classes (candump -e names)"},
    "controller": {**_NAMES, "description": "bus_error: controller problems"},
    "protocol": {**_NAMES, "description": "bus_error: protocol violation types"},
    "location": {
        "type": "string",
        "description": "bus_error: where in the frame the protocol violation was",
    },
    "transceiver": {"type": "string", "description": "bus_error: wiring status"},
    "lost_arbitration_bit": {
        "type": "integer",
        "description": "bus_error: the bit arbitration was lost in",
    },
    "tx_errors": {**_COUNTER, "description": "bus_error: transmit error counter"},
    "rx_errors": {**_COUNTER, "description": "bus_error: receive error counter"},
    "bus_state": {**_BUS_STATE, "description": "bus_error: the channel's state after it"},
    "malformed": {
        "type": "string",
        "description": "bus_error: why the error frame does not fit linux/can/error.h",
    },
}


def bus_state_schema() -> dict[str, Any]:
    """A CAN channel's controller state, followed from its error frames."""
    schema = _envelope(
        TOPIC_CAN_BUS_STATE,
        "CAN bus state",
        "The error state of the CAN controller of a channel, at each change (state or "
        "error counters) and at least every second while error frames come in.",
    )
    counts = {
        count_key(name): {"type": "integer", "minimum": 0}
        for name in (*CLASS_NAMES, UNSPECIFIED, UNKNOWN_CLASS)
    }
    schema["properties"].update(
        {
            "state": {**_BUS_STATE, "description": "error-active .. bus-off"},
            "level": {
                "type": "integer",
                "minimum": 0,
                "maximum": len(BUS_STATES) - 1,
                "description": "the state as a number to plot: 0 error-active, "
                "1 error-warning, 2 error-passive, 3 bus-off",
            },
            "since": {"type": "number", "description": "when the state began"},
            "tx_errors": {
                **_COUNTER,
                "description": "transmit error counter (last reported; absent until one is)",
            },
            "rx_errors": {**_COUNTER, "description": "receive error counter (last reported)"},
            "error_frames": {"type": "integer", "minimum": 0, "description": "error frames so far"},
            "counts": {
                "type": "object",
                "properties": counts,
                "description": "error frames so far by class (candump -e names, '_' for '-')",
            },
        }
    )
    schema["required"] += ["state", "level", "error_frames", "counts"]
    return schema


def ardupilot_schemas() -> dict[str, dict[str, Any]]:
    """What an ArduPilot mount driver saw in `demo --ardupilot`: the attitude it reported
    and the targets ArduPilot's mount and camera libraries asked of it."""
    mount = _envelope(
        TOPIC_ARDUPILOT_MOUNT,
        "ArduPilot mount attitude",
        "The attitude the mount driver reported to ArduPilot (mount:set_attitude_euler).",
    )
    targets = _envelope(
        TOPIC_ARDUPILOT_TARGETS,
        "ArduPilot mount target",
        "What ArduPilot's mount library (mount:get_rate_target, get_angle_target, "
        "get_location_target) or camera library (camera:get_state) asks, at each change.",
    )
    _add_described(mount, MOUNT_FIELDS)
    _add_described(targets, TARGET_FIELDS, TARGET_ENUMS)
    mount["required"] += list(MOUNT_FIELDS)
    targets["required"].append("target")
    return {TOPIC_ARDUPILOT_MOUNT: mount, TOPIC_ARDUPILOT_TARGETS: targets}


# The link diagnostics a replay marks its span with (state "replay" where it begins,
# "replay_end" where it ends): ``compare`` takes what lies between as the replay.
REPLAY_MARK_FIELDS: dict[str, dict[str, str]] = {
    "flight": {"type": "string", "description": "replay marks: the flight replayed"},
    "flight_from": {
        "type": "number",
        "description": "replay marks: where the replayed span begins, in the flight's time",
    },
    "flight_to": {"type": "number", "description": "replay marks: where it ends"},
    "span_start_s": {
        "type": "number",
        "description": "replay marks: where the span begins, seconds into the flight",
    },
    "span_end_s": {"type": "number", "description": "replay marks: where it ends, the same"},
    "speed": {"type": "number", "description": "replay marks: times the flight's speed"},
}


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
            "line": {"type": "integer", "description": "line number in the input file"},
            "state": {
                "type": "string",
                "description": "link diagnostics: the new state (open, connected, lost, ...)",
            },
            "peer": {"type": "string", "description": "link diagnostics: the other end"},
            "retry_in_s": {"type": "number", "description": "link diagnostics: next attempt"},
            "down_s": {
                "type": "number",
                "description": "link diagnostics: how long a lost link was gone, once back",
            },
            "lost_at": {
                "type": "number",
                "description": "link diagnostics: when a link that is back was lost (Unix s)",
            },
            "packets": {"type": "integer", "description": "pcap packets concerned"},
            "packets_read": {"type": "integer", "description": "pcap packets read until then"},
            "frames_read": {"type": "integer", "description": "frames read until then"},
            "missing_bytes": {"type": "integer", "description": "bytes a capture lacks"},
            **REPLAY_MARK_FIELDS,
            **ERROR_FRAME_FIELDS,
        }
    )
    diag["required"] += ["kind", "detail", "raw"]
    out[TOPIC_DIAGNOSTICS] = diag
    out[TOPIC_ANALYSIS_RESPONSE] = response_schema()
    out[TOPIC_CHECK_STEPS] = check_steps_schema()
    out[TOPIC_CAN_BUS_STATE] = bus_state_schema()
    out.update(ardupilot_schemas())
    assert set(out) == set(TOPICS)
    return out


def schema_filename(topic: str) -> str:
    """'/gimbal/command' -> 'gimbal.command.schema.json'."""
    return topic.strip("/").replace("/", ".") + ".schema.json"
