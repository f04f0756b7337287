"""A Foxglove WebSocket client for the tests, as Foxglove speaks it (subprotocol foxglove.sdk.v1).

It reads ``serverInfo`` and ``advertise``, subscribes to every advertised channel (unless
told not to), and keeps every ``messageData`` it gets (binary opcode 1: subscription id
u32, log time u64, little-endian, then the message bytes).
"""

from __future__ import annotations

import json
import struct
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

SDK_SUBPROTOCOL = "foxglove.sdk.v1"
MESSAGE_DATA = 0x01


@dataclass(frozen=True)
class LiveMessage:
    topic: str
    log_time: int
    data: bytes


class FoxgloveClient:
    """Connects at once; ``reading=False`` stops reading after subscribing (a slow client)."""

    def __init__(self, url: str, *, subscribe: bool = True, reading: bool = True) -> None:
        self._cm = connect(
            url, subprotocols=[SDK_SUBPROTOCOL], max_size=None, open_timeout=10, close_timeout=2
        )
        self.ws = self._cm.__enter__()
        self.server_info: dict[str, Any] = {}
        self.channels: dict[int, dict[str, Any]] = {}  # channel id -> advertised channel
        self.first_advertise: list[dict[str, Any]] | None = None
        self.messages: list[LiveMessage] = []
        self.closed = threading.Event()
        self._subscribe = subscribe
        self._reading = reading
        self._subscriptions: dict[int, int] = {}  # subscription id -> channel id
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            while True:
                frame = self.ws.recv()
                if isinstance(frame, str):
                    self._control(json.loads(frame))
                elif frame[0] == MESSAGE_DATA:
                    sub_id, log_time = struct.unpack_from("<IQ", frame, 1)
                    with self._lock:
                        topic = self.channels[self._subscriptions[sub_id]]["topic"]
                        self.messages.append(LiveMessage(topic, log_time, bytes(frame[13:])))
        except ConnectionClosed:
            pass
        finally:
            self.closed.set()

    def _control(self, message: dict[str, Any]) -> None:
        op = message.get("op")
        if op == "serverInfo":
            self.server_info = message
        elif op == "advertise":
            with self._lock:
                if self.first_advertise is None:
                    self.first_advertise = list(message["channels"])
                for channel in message["channels"]:
                    self.channels[channel["id"]] = channel
            if self._subscribe:
                self.subscribe([channel["id"] for channel in message["channels"]])
            if not self._reading:  # a slow client: from now on it reads nothing
                self.closed.wait()

    def subscribe(self, channel_ids: list[int]) -> None:
        subscriptions = []
        with self._lock:
            for channel_id in channel_ids:
                sub_id = len(self._subscriptions) + 1
                self._subscriptions[sub_id] = channel_id
                subscriptions.append({"id": sub_id, "channelId": channel_id})
        self.ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))

    def wait_for(self, condition: Callable[[], bool], timeout: float = 10.0) -> bool:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with self._lock:
                if condition():
                    return True
            time.sleep(0.02)
        return False

    def by_topic(self) -> dict[str, list[tuple[int, bytes]]]:
        with self._lock:
            out: dict[str, list[tuple[int, bytes]]] = {}
            for message in self.messages:
                out.setdefault(message.topic, []).append((message.log_time, message.data))
            return out

    def channels_by_topic(self) -> dict[str, dict[str, Any]]:
        with self._lock:
            return {channel["topic"]: channel for channel in self.channels.values()}

    def close(self) -> None:
        self.closed.set()
        self._cm.__exit__(None, None, None)
        self._thread.join(5)
