"""The channels of a recording being written: each topic's schema and id, registered once."""

from __future__ import annotations

from typing import Any

from analyzer.mcapio.channels import ROLE_KEY, ChannelSpec, MessageTee, channel_spec
from analyzer.mcapio.write.chunked_writer import ChunkedWriter


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
    the per-message path to read directly. A ``tee`` (the live server) is told of every
    channel registered."""

    def __init__(
        self,
        writer: ChunkedWriter,
        schemas: dict[str, dict[str, Any]],
        tee: MessageTee | None = None,
    ) -> None:
        self._writer = writer
        self._schemas = schemas
        self._tee = tee
        self._schema_ids: dict[str, int] = {}
        self.ids: dict[str, int] = {}
        self.sequence: dict[int, int] = {}

    def channel(self, topic: str, role: str) -> int:
        """The channel id of ``topic``, registering it (and its schema) the first time."""
        channel_id = self.ids.get(topic)
        if channel_id is not None:
            return channel_id
        return self.register(channel_spec(topic, role, self._schemas))

    def register(self, spec: ChannelSpec, metadata: dict[str, str] | None = None) -> int:
        """The channel id of ``spec.topic``, registered with its schema and ``metadata`` (next
        to its role) the first time: every channel of the file, camera video included."""
        channel_id = self.ids.get(spec.topic)
        if channel_id is not None:
            return channel_id
        schema_id = self._schema_ids.get(spec.schema_name)
        if schema_id is None:
            schema_id = self._writer.register_schema(
                spec.schema_name, spec.schema_encoding, spec.schema
            )
            self._schema_ids[spec.schema_name] = schema_id
        channel_id = self._writer.register_channel(
            spec.topic, spec.message_encoding, schema_id, {ROLE_KEY: spec.role, **(metadata or {})}
        )
        if self._tee is not None:
            self._tee.add_channel(channel_id, spec)
        self.ids[spec.topic] = channel_id
        self.sequence[channel_id] = 0
        return channel_id

    def add_message(self, channel_id: int, log_time: int, data: bytes) -> None:
        """One message on a registered channel, numbered in its sequence (also to the tee)."""
        self.sequence[channel_id] += 1
        self._writer.add_message(channel_id, log_time, data, log_time, self.sequence[channel_id])
        if self._tee is not None:
            self._tee.add_message(channel_id, log_time, data)
