"""FoxgloveLive: a sink serving the decoded stream to Foxglove with the foxglove-sdk server.

It advertises the channels of a recording (same topics, schema names, JSON Schemas and role
metadata: ``analyzer.mcapio.channels.channel_spec``), every one a recording can hold from the
start, and sends every message as it is written. Advertising them all before any client
connects is deliberate: foxglove-sdk 0.30 may answer a client that subscribes at once to a
channel created while it is connected with "Unknown channel ID" (the panel would stay empty
until it reconnects); channels that exist when a client connects are advertised safely.

Fed by a recording (``McapSink(..., tee=live)``) it sends the very bytes written to the
file; without one (``monitor``) it encodes batches itself with the same encoders. Sending
never waits for a client: the SDK queues at most ``backlog`` messages per client and drops
the oldest when a client falls behind.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import foxglove
from foxglove import Channel, Context, Schema
from foxglove._foxglove_py import BaseChannel
from foxglove.websocket import ChannelView, Client, ServerListener, WebSocketServer

from analyzer.errors import UsageError
from analyzer.live.options import ListenAddress, listen_words
from analyzer.live.sdk_log import sdk_reports
from analyzer.mcapio.channels import (
    ROLE_EVENT,
    ROLE_KEY,
    ROLE_RAW,
    ROLE_VIEW,
    TOPIC_CAN_FRAMES,
    TOPIC_STREAM_BYTES,
    ChannelSpec,
    can_frame_json,
    channel_spec,
    json_bytes,
    known_channel_specs,
    stream_chunk_json,
)
from analyzer.mcapio.foxglove import VIEW_INPUT_TOPICS, FoxgloveViews
from analyzer.mcapio.log_time import time_ns
from analyzer.pipeline import Batch
from analyzer.protocol.types import CanFrame
from analyzer.sources.netutil import address

SERVER_NAME = "gimbal-analyzer"
DEFAULT_BACKLOG = 1024  # messages queued per client before the oldest are dropped (SDK default)
STOP_WAIT_S = 1.0  # how long close() waits for the SDK server to stop
LINGER_S = 0.25  # time watching clients get for the last messages before the server stops


def _default_schemas() -> dict[str, dict[str, Any]]:
    from analyzer.protocol.schema import topic_schemas

    return topic_schemas()


@dataclass(frozen=True, slots=True)
class LiveStatus:
    """What the live server is doing, for status lines."""

    url: str
    clients: int  # clients connected (as the SDK's log tells), at least those watching
    watching: int  # clients subscribed to at least one channel
    subscriptions: int
    channels: int  # advertised
    messages: int  # messages handed to the SDK
    drop_reports: int  # SDK reports of a slow client's messages dropped (not a count of them)
    last_drop: float  # time.time() of the last such report, 0 if none
    refused: int  # connections refused by the SDK (a client with another subprotocol)
    errors: int  # messages the SDK refused (the server goes on)


class _Subscriptions(ServerListener):
    """SDK server listener: who is subscribed to which channel (called from SDK threads)."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.pairs: set[tuple[int, int]] = set()  # (client id, SDK channel id)

    def on_subscribe(self, client: Client, channel: ChannelView) -> None:
        with self.lock:
            self.pairs.add((client.id, channel.id))

    def on_unsubscribe(self, client: Client, channel: ChannelView) -> None:
        with self.lock:
            self.pairs.discard((client.id, channel.id))

    def counts(self) -> tuple[int, int]:
        with self.lock:
            return len({client for client, _ in self.pairs}), len(self.pairs)


class FoxgloveLive:
    """Sink and ``MessageTee`` (``analyzer.mcapio.channels``) serving Foxglove live.

    Starts listening at once (``UsageError`` with one line when it cannot, e.g. the port is
    taken); ``channels`` (the cameras') are advertised from the start with those a
    recording can always hold. ``add_channel`` / ``add_message`` are called by a recording
    for every channel and message it writes; with ``encode`` (no recording to feed it)
    ``handle`` encodes each batch itself. ``close`` stops the server and disconnects the
    clients. Nothing here raises into the recording: a message the SDK refuses is counted
    in ``errors``.
    """

    def __init__(
        self,
        listen: ListenAddress,
        *,
        schemas: dict[str, dict[str, Any]] | None = None,
        backlog: int = DEFAULT_BACKLOG,
        encode: bool = False,
        channels: Sequence[ChannelSpec] = (),
    ) -> None:
        self.listen = listen
        self.encode = encode
        self.messages = 0
        self.errors = 0
        self._schemas = _default_schemas() if schemas is None else dict(schemas)
        self._channels: list[BaseChannel | None] = []  # by the recording's channel id
        self._by_topic: dict[str, tuple[ChannelSpec, BaseChannel]] = {}  # advertised ones
        self._own: dict[str, BaseChannel | None] = {}  # by topic, when encoding itself
        self._views = FoxgloveViews()
        self._subscriptions = _Subscriptions()
        self._reports_at_start = sdk_reports()  # also starts forwarding the SDK's log
        self._context = Context()
        try:
            self._server: WebSocketServer | None = foxglove.start_server(
                name=SERVER_NAME,
                host=listen.host,
                port=listen.port,
                context=self._context,
                server_listener=self._subscriptions,
                message_backlog_size=backlog,
            )
        except Exception as exc:
            where = address(listen.host, listen.port)
            raise UsageError(f"--foxglove: cannot listen on {where} ({exc})") from None
        self.port = self._server.port
        self.url = f"ws://{address(listen.host, self.port)}"
        for spec in [*known_channel_specs(self._schemas), *channels]:
            self._advertise(spec)

    # -- MessageTee: fed by a recording ---------------------------------------------------------

    def add_channel(self, channel_id: int, spec: ChannelSpec) -> None:
        channels = self._channels
        if len(channels) <= channel_id:
            channels.extend([None] * (channel_id + 1 - len(channels)))
        channels[channel_id] = self._channel_for(spec)

    def advertise(self, spec: ChannelSpec) -> None:
        self._channel_for(spec)

    def add_message(self, channel_id: int, log_time: int, data: bytes) -> None:
        channel = self._channels[channel_id] if channel_id < len(self._channels) else None
        if channel is not None:
            self._log(channel, log_time, data)

    def _channel_for(self, spec: ChannelSpec) -> BaseChannel | None:
        """The advertised channel of ``spec`` (advertised now if it is a new one)."""
        known = self._by_topic.get(spec.topic)
        return known[1] if known is not None and known[0] == spec else self._advertise(spec)

    def _advertise(self, spec: ChannelSpec) -> BaseChannel | None:
        schema = Schema(name=spec.schema_name, encoding=spec.schema_encoding, data=spec.schema)
        try:
            channel = Channel(
                spec.topic,
                schema=schema,
                message_encoding=spec.message_encoding,
                context=self._context,
                metadata={ROLE_KEY: spec.role},
            ).base  # the SDK's own channel: logging bytes through it skips a Python layer
        except Exception:
            self.errors += 1
            return None
        self._by_topic[spec.topic] = (spec, channel)
        return channel

    def _log(self, channel: BaseChannel, log_time: int, data: bytes) -> None:
        try:
            channel.log(data, log_time)
        except Exception:  # never into the recording
            self.errors += 1
        else:
            self.messages += 1

    # -- Sink ------------------------------------------------------------------------------------

    def handle(self, batch: Batch) -> None:
        """With ``encode`` (no recording feeds it): encode the batch as a recording would."""
        if not self.encode or self._server is None:
            return
        send = self._send
        for item in batch.items:
            if isinstance(item, CanFrame):
                send(TOPIC_CAN_FRAMES, ROLE_RAW, item.time, can_frame_json(item))
            else:
                send(TOPIC_STREAM_BYTES, ROLE_RAW, item.time, stream_chunk_json(item))
        views = self._views
        for event in batch.events:
            topic = event.topic
            send(topic, ROLE_EVENT, event.time, json_bytes(event.to_dict()))
            if topic in VIEW_INPUT_TOPICS:
                for view_topic, message in views.views(event):
                    send(view_topic, ROLE_VIEW, event.time, json_bytes(message))

    def _send(self, topic: str, role: str, seconds: float, data: bytes) -> None:
        if topic in self._own:
            channel = self._own[topic]
        else:
            channel = self._own[topic] = self._channel_for(channel_spec(topic, role, self._schemas))
        if channel is not None:
            self._log(channel, time_ns(seconds), data)

    def close(self) -> None:
        """Stop serving. Watching clients get ``LINGER_S`` to receive the last messages (the
        SDK's stop drops what is still queued). The SDK's stop waits for every connection to
        close, which a client that stopped reading delays until its own timeout: that wait
        runs in a thread of its own, given ``STOP_WAIT_S`` before the caller goes on."""
        server, self._server = self._server, None
        if server is not None:
            if self._subscriptions.counts()[0]:
                time.sleep(LINGER_S)
            stopper = threading.Thread(target=server.stop, name="foxglove-stop", daemon=True)
            stopper.start()
            stopper.join(STOP_WAIT_S)

    # -- what it is doing ------------------------------------------------------------------------

    @property
    def everywhere(self) -> bool:
        return self.listen.everywhere

    def describe(self) -> str:
        """Where it listens, in words: all interfaces is said so, with the address."""
        return listen_words(self.listen, self.port)

    def status(self) -> LiveStatus:
        watching, subscriptions = self._subscriptions.counts()
        now = sdk_reports()
        start = self._reports_at_start
        connected = (now.connected - start.connected) - (now.disconnected - start.disconnected)
        return LiveStatus(
            url=self.url,
            clients=max(connected, watching),
            watching=watching,
            subscriptions=subscriptions,
            channels=len(self._by_topic),
            messages=self.messages,
            drop_reports=now.outbox_full - start.outbox_full,
            last_drop=now.last_outbox_full if now.outbox_full > start.outbox_full else 0.0,
            refused=now.refused - start.refused,
            errors=self.errors,
        )


def status_words(live: FoxgloveLive, now: float | None = None) -> str:
    """The live server in a few words for a status line: clients, and slow-client drops."""
    status = live.status()
    now = time.time() if now is None else now
    plural = "" if status.clients == 1 else "s"
    parts = [f"foxglove :{live.port} {status.clients} client{plural}"]
    if status.drop_reports:
        ago = now - status.last_drop
        parts.append(f"SLOW CLIENT, messages to it dropped ({ago:.0f} s ago)")
    if status.refused:
        parts.append(f"{status.refused} refused (old protocol?)")
    return " ".join(parts)
