"""Channel layout of a recording: raw channels, their JSON encoding and the channel roles."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any, Protocol

import orjson

from analyzer.mcapio.foxglove import VIEW_SCHEMAS, view_schema
from analyzer.protocol.types import CanFrame, StreamChunk, hexstr

TOPIC_CAN_FRAMES = "/can/frames"
TOPIC_STREAM_BYTES = "/stream/bytes"
RAW_TOPICS = (TOPIC_CAN_FRAMES, TOPIC_STREAM_BYTES)
# Where the gimbal points (views of the feedback, commands and UAV status): the frames of
# world, aircraft, gimbal and camera, and the 3D scene (aircraft, field of view, target).

# Name of the metadata record describing the recording, and of the one written at the end
# with counts gathered while writing (so `info` needs no scan of a finalised file).
METADATA_NAME = "gimbal-analyzer"
STATS_METADATA_NAME = "gimbal-analyzer.stats"

# Channel metadata key telling what a channel holds: decoded events, raw input or a
# Foxglove view derived from events.
ROLE_KEY = "role"
ROLE_EVENT = "event"
ROLE_RAW = "raw"
ROLE_VIEW = "view"

SCHEMA_DIALECT = "https://json-schema.org/draft/2020-12/schema"

CAN_FRAME_SCHEMA: dict[str, Any] = {
    "$schema": SCHEMA_DIALECT,
    "title": "gimbal_analyzer.CanFrame",
    "description": "One CAN frame exactly as received (lossless; re-decodable).",
    "type": "object",
    "properties": {
        "time": {"type": "number", "description": "seconds (Unix time) of reception"},
        "id": {"type": "integer", "minimum": 0, "description": "CAN identifier"},
        "extended": {"type": "boolean", "description": "29-bit identifier"},
        "dlc": {
            "type": "integer",
            "minimum": 0,
            "description": "number of data bytes; of a remote frame, the length it requests",
        },
        "data": {"type": "string", "description": "data bytes, hex pairs separated by spaces"},
        "channel": {"type": "string", "description": "CAN channel / interface name"},
        "remote": {"type": "boolean", "description": "remote transmission request"},
        "error": {"type": "boolean", "description": "error frame"},
        "fd": {"type": "boolean", "description": "CAN FD frame"},
        "direction": {"type": "string", "description": "'rx' / 'tx' when the source says so"},
    },
    "required": ["time", "id", "extended", "dlc", "data"],
}

STREAM_BYTES_SCHEMA: dict[str, Any] = {
    "$schema": SCHEMA_DIALECT,
    "title": "gimbal_analyzer.StreamChunk",
    "description": "Bytes read from a TCP / UART stream in one go (lossless; re-decodable).",
    "type": "object",
    "properties": {
        "time": {"type": "number", "description": "seconds (Unix time) of the read"},
        "data": {"type": "string", "description": "the bytes, hex pairs separated by spaces"},
        "size": {"type": "integer", "minimum": 0, "description": "number of bytes"},
        "source": {"type": "string", "description": "stream name (address, device)"},
        "direction": {
            "type": "string",
            "enum": ["gs_to_idu", "idu_to_gs", ""],
            "description": "ground station -> IDU, IDU -> ground station, or unknown",
        },
    },
    "required": ["time", "data", "source"],
}

TRUE_FALSE = ("false", "true")
_STRING_CACHE: dict[str, str] = {}


def _json_str(value: str) -> str:
    """A JSON string literal, cached (channel names and directions repeat endlessly)."""
    text = _STRING_CACHE.get(value)
    if text is None:
        text = json.dumps(value)
        if len(_STRING_CACHE) < 1024:
            _STRING_CACHE[value] = text
    return text


def _json_time(value: float) -> str:
    return repr(float(value)) if math.isfinite(value) else "0.0"


FRAME_TAILS: dict[tuple[str, bool, bool, bool, str], str] = {}


def frame_tail(frame: CanFrame) -> str:
    """The end of a frame's message from its data on: the same for most frames of a file."""
    key = (frame.channel, frame.is_remote, frame.is_error, frame.is_fd, frame.direction)
    tail = FRAME_TAILS.get(key)
    if tail is None:
        tail = (
            f'","channel":{_json_str(frame.channel)},'
            f'"remote":{TRUE_FALSE[frame.is_remote]},"error":{TRUE_FALSE[frame.is_error]},'
            f'"fd":{TRUE_FALSE[frame.is_fd]},"direction":{_json_str(frame.direction)}}}'
        )
        if len(FRAME_TAILS) < 1024:
            FRAME_TAILS[key] = tail
    return tail


def can_frame_json(frame: CanFrame) -> bytes:
    """The /can/frames message of one frame (hand-built: this runs for every frame)."""
    t = frame.time
    stamp = repr(t) if type(t) is float and t - t == 0 else _json_time(t)  # not NaN, inf
    tail = FRAME_TAILS.get(
        (frame.channel, frame.is_remote, frame.is_error, frame.is_fd, frame.direction)
    ) or frame_tail(frame)
    return (
        f'{{"time":{stamp},"id":{frame.can_id},"extended":{TRUE_FALSE[frame.extended]},'
        f'"dlc":{frame.dlc},"data":"{frame.data.hex(" ").upper()}{tail}'
    ).encode()


# From here up to 1e16, orjson writes a float as repr does (the shortest digits that
# read back the same, no exponent): the writer's fast path for frame times
# (tests/test_mcap_frame_messages.py).
FLOAT_AS_REPR_FROM = 1e-4
FRAME_OPEN = b'{"time":'
# (CAN ID, extended, data length, channel, error, fd, direction) -> frame_parts
FramePartsKey = tuple[int, bool, int, str, bool, bool, str]
FRAME_PARTS: dict[FramePartsKey, tuple[bytes, bytes]] = {}


def frame_parts(frame: CanFrame, key: FramePartsKey) -> tuple[bytes, bytes]:
    """The /can/frames message of a frame that is not remote, between its time and its data
    and after its data: the same for every frame of one ``key`` (kept in FRAME_PARTS, made
    by the writer's loop, the one place that reads it)."""
    middle = (
        f',"id":{frame.can_id},"extended":{TRUE_FALSE[frame.extended]},'
        f'"dlc":{len(frame.data)},"data":"'
    )
    parts = (middle.encode(), frame_tail(frame).encode())
    if len(FRAME_PARTS) < 4096:
        FRAME_PARTS[key] = parts
    return parts


def stream_chunk_json(chunk: StreamChunk) -> bytes:
    """The /stream/bytes message of one chunk."""
    return (
        f'{{"time":{_json_time(chunk.time)},"data":"{hexstr(chunk.data)}",'
        f'"size":{len(chunk.data)},"source":{_json_str(chunk.source)},'
        f'"direction":{_json_str(chunk.direction)}}}'
    ).encode()


def can_frame_from_dict(obj: dict[str, Any]) -> CanFrame:
    return CanFrame(
        time=float(obj["time"]),
        can_id=int(obj["id"]),
        data=bytes.fromhex(str(obj.get("data", ""))),
        extended=bool(obj.get("extended", True)),
        channel=str(obj.get("channel", "")),
        is_remote=bool(obj.get("remote", False)),
        is_error=bool(obj.get("error", False)),
        is_fd=bool(obj.get("fd", False)),
        direction=str(obj.get("direction", "")),
        remote_dlc=int(obj.get("dlc", 0)) if obj.get("remote") else 0,
    )


def stream_chunk_from_dict(obj: dict[str, Any]) -> StreamChunk:
    return StreamChunk(
        time=float(obj["time"]),
        data=bytes.fromhex(str(obj.get("data", ""))),
        source=str(obj.get("source", "stream")),
        direction=str(obj.get("direction", "")),
    )


def schema_name(topic: str) -> str:
    """'/gimbal/command' -> 'gimbal_analyzer.gimbal.command'."""
    return "gimbal_analyzer." + topic.strip("/").replace("/", ".")


def permissive_schema(topic: str) -> dict[str, Any]:
    """Schema for a topic the core has no schema for (e.g. /can/other)."""
    return {
        "$schema": SCHEMA_DIALECT,
        "title": schema_name(topic),
        "description": f"events on {topic}",
        "type": "object",
        "properties": {
            "topic": {"type": "string"},
            "time": {"type": "number"},
            "source": {"type": "string"},
            "warnings": {"type": "array", "items": {"type": "string"}},
        },
        "required": ["topic", "time"],
    }


def json_default(value: Any) -> Any:
    if isinstance(value, (bytes, bytearray, memoryview)):
        return bytes(value).hex(" ").upper()
    if isinstance(value, (set, frozenset, tuple)):
        return list(value)
    return str(value)


# One encoder for every event and view message (json.dumps with options builds a new one per
# call). Events never hold reference cycles, so the cycle check is skipped.
encode_json = json.JSONEncoder(
    separators=(",", ":"), default=json_default, check_circular=False
).encode
ORJSON_OPTIONS = orjson.OPT_NON_STR_KEYS


def json_bytes(value: Any) -> bytes:
    """An event or view message as compact UTF-8 JSON, as every message of a recording is
    written (orjson: several times faster than the json module, which is used only for
    what orjson refuses, such as an integer beyond 64 bits)."""
    try:
        return orjson.dumps(value, default=json_default, option=ORJSON_OPTIONS)
    except (orjson.JSONEncodeError, TypeError):
        return encode_json(value).encode()


@dataclass(frozen=True, slots=True)
class ChannelSpec:
    """What a channel of a recording is: topic, role, schema name and JSON Schema (as bytes).

    The MCAP writer registers exactly these, and the live Foxglove server advertises them.
    """

    topic: str
    role: str
    schema_name: str
    schema: bytes
    message_encoding: str = "json"
    schema_encoding: str = "jsonschema"


def channel_spec(topic: str, role: str, schemas: dict[str, dict[str, Any]]) -> ChannelSpec:
    """The channel of ``topic`` with role raw / view / event; ``schemas`` are the event
    topics' JSON Schemas (``analyzer.protocol.schema.topic_schemas``)."""
    if role == ROLE_RAW:
        schema = CAN_FRAME_SCHEMA if topic == TOPIC_CAN_FRAMES else STREAM_BYTES_SCHEMA
        name = str(schema["title"])
    elif role == ROLE_VIEW:
        name, schema = view_schema(topic)
    else:
        name = schema_name(topic)
        schema = schemas.get(topic) or permissive_schema(topic)
    data = json.dumps(schema, separators=(",", ":")).encode()
    return ChannelSpec(topic, role, name, data)


class MessageTee(Protocol):
    """Gets every channel and message a recording writes, with the very bytes written
    (the live Foxglove server, ``analyzer.live.server``)."""

    def add_channel(self, channel_id: int, spec: ChannelSpec) -> None: ...

    def advertise(self, spec: ChannelSpec) -> None:
        """A channel the recording will have (a camera's), told before its first message."""

    def add_message(self, channel_id: int, log_time: int, data: bytes) -> None: ...


def known_channel_specs(schemas: dict[str, dict[str, Any]]) -> list[ChannelSpec]:
    """Every channel a recording can hold: the raw ones, one per event topic with a schema
    and the Foxglove views (a recording holds those that got messages, as they come)."""
    return [
        *(channel_spec(topic, ROLE_RAW, schemas) for topic in RAW_TOPICS),
        *(channel_spec(topic, ROLE_EVENT, schemas) for topic in schemas),
        *(channel_spec(topic, ROLE_VIEW, schemas) for topic in VIEW_SCHEMAS),
    ]
