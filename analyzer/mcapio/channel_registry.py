"""The channels of a recording being written: each topic's schema and id, registered once."""

from __future__ import annotations

import json
from typing import Any

from analyzer.mcapio.channels import (
    CAN_FRAME_SCHEMA,
    ROLE_KEY,
    ROLE_RAW,
    ROLE_VIEW,
    STREAM_BYTES_SCHEMA,
    TOPIC_CAN_FRAMES,
    permissive_schema,
    schema_name,
)
from analyzer.mcapio.chunked_writer import ChunkedWriter
from analyzer.mcapio.foxglove import VIEW_SCHEMAS


def default_schemas() -> dict[str, dict[str, Any]]:
    """JSON schemas of the event topics, from the command table (empty when unavailable)."""
    try:
        from analyzer.protocol.schema import topic_schemas
    except ImportError:
        return {}
    return topic_schemas()


class ChannelRegistry:
    """Topic -> channel id of one file, each channel registered with its schema at first use.

    ``ids`` and ``sequence`` (channel id -> number of the last message) are plain dicts for
    the per-message path to read directly."""

    def __init__(self, writer: ChunkedWriter, schemas: dict[str, dict[str, Any]]) -> None:
        self._writer = writer
        self._schemas = schemas
        self._schema_ids: dict[str, int] = {}
        self.ids: dict[str, int] = {}
        self.sequence: dict[int, int] = {}

    def channel(self, topic: str, role: str) -> int:
        """The channel id of ``topic``, registering it (and its schema) the first time."""
        channel_id = self.ids.get(topic)
        if channel_id is not None:
            return channel_id
        if role == ROLE_RAW:
            schema = CAN_FRAME_SCHEMA if topic == TOPIC_CAN_FRAMES else STREAM_BYTES_SCHEMA
            name = str(schema["title"])
        elif role == ROLE_VIEW:
            name, schema = VIEW_SCHEMAS[topic]
        else:
            name = schema_name(topic)
            schema = self._schemas.get(topic) or permissive_schema(topic)
        schema_id = self._schema_ids.get(name)
        if schema_id is None:
            data = json.dumps(schema, separators=(",", ":")).encode()
            schema_id = self._writer.register_schema(name, "jsonschema", data)
            self._schema_ids[name] = schema_id
        channel_id = self._writer.register_channel(topic, "json", schema_id, {ROLE_KEY: role})
        self.ids[topic] = channel_id
        self.sequence[channel_id] = 0
        return channel_id
