"""A message as a recording stores it, the role of its channel, and the item it holds."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from analyzer.mcapio.channels import (
    RAW_TOPICS,
    ROLE_EVENT,
    ROLE_KEY,
    ROLE_RAW,
    ROLE_VIEW,
    TOPIC_CAN_FRAMES,
    TOPIC_STREAM_BYTES,
    can_frame_from_dict,
    stream_chunk_from_dict,
)
from analyzer.mcapio.foxglove import VIEW_SCHEMAS
from analyzer.mcapio.read.ros_can import RosFrameError, ros_can_role, ros_frame
from analyzer.pipeline import RawItem
from analyzer.protocol.types import BAD_FRAME, CanFrame, Event, diagnostic

# A channel of another writer that this tool cannot read (neither JSON nor CAN frames).
ROLE_OTHER = "other"

# tally(topic, role, log_time): called for every message a sequential read meets
MessageTally = Callable[[str, str, int], None]
# wanted(topic, role): whether a read yields the messages of a channel
ChannelFilter = Callable[[str, str], bool]


@dataclass(slots=True)
class ReadPosition:
    """How far a read of a recording has got in its file (bytes), for a progress line."""

    bytes: int = 0


@dataclass(frozen=True, slots=True)
class RawMessage:
    """One message as stored: channel topic and role, log time (ns) and the JSON bytes."""

    topic: str
    role: str
    log_time: int
    data: bytes


@dataclass(frozen=True, slots=True)
class ChannelKind:
    """What a channel holds: its topic, role, schema and encodings, and whether this tool
    wrote it (its metadata names its role)."""

    topic: str
    role: str
    schema: str
    schema_encoding: str
    message_encoding: str
    ours: bool

    def describe(self) -> str:
        schema = self.schema or "(no schema)"
        encoding = f"{self.schema_encoding}/" if self.schema_encoding else ""
        return f"{self.topic}  {schema} ({encoding}{self.message_encoding or '?'})"


def channel_kind(
    topic: str,
    metadata: dict[str, str],
    schema: object | None,
    message_encoding: str,
) -> ChannelKind:
    """The kind of a channel from its record and its schema record (None when it has none)."""
    name = str(getattr(schema, "name", "") or "")
    role = channel_role(topic, metadata, name, message_encoding)
    encoding = str(getattr(schema, "encoding", "") or "")
    return ChannelKind(topic, role, name, encoding, message_encoding, ROLE_KEY in metadata)


def channel_role(
    topic: str, metadata: dict[str, str], schema_name: str = "", message_encoding: str = ""
) -> str:
    """Role of a channel: from its metadata, else from its schema and message encoding, else
    guessed from the topic (other writers)."""
    role = metadata.get(ROLE_KEY)
    if role:
        return role
    ros = ros_can_role(schema_name, message_encoding)
    if ros:
        return ros
    if message_encoding not in ("", "json"):
        return ROLE_OTHER
    if topic in RAW_TOPICS:
        return ROLE_RAW
    if topic in VIEW_SCHEMAS:
        return ROLE_VIEW
    return ROLE_EVENT


def raw_item(topic: str, obj: Any) -> RawItem | None:
    """The frame or chunk of a raw-channel message (None for other topics)."""
    if topic == TOPIC_CAN_FRAMES:
        return can_frame_from_dict(obj)
    if topic == TOPIC_STREAM_BYTES:
        return stream_chunk_from_dict(obj)
    return None


def ros_item(message: RawMessage) -> CanFrame | Event:
    """The CAN frame of a ROS bag's message, or a ``bad_frame`` diagnostic saying why not."""
    try:
        return ros_frame(message.role, message.data, message.topic, message.log_time)
    except RosFrameError as exc:
        return diagnostic(
            message.log_time / 1e9,
            message.topic,
            BAD_FRAME,
            f"{message.topic}: message not read as a CAN frame: {exc}",
            message.data,
        )
