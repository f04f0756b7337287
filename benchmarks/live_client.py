"""A Foxglove WebSocket client for benchmarks/live_load.py: subscribes to every channel the
server advertises and counts what it receives, in a process of its own (its CPU is not the
recorder's). Prints ``subscribed N`` once subscribed, ``received MESSAGES BYTES`` at the end.

    python benchmarks/live_client.py ws://127.0.0.1:8765
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

SUBPROTOCOL = "foxglove.sdk.v1"


class LiveClient:
    """This script in a process of its own, subscribed to every channel."""

    def __init__(self, url: str) -> None:
        script = Path(__file__)
        self.proc = subprocess.Popen(
            [sys.executable, str(script), url], stdout=subprocess.PIPE, text=True, encoding="utf-8"
        )
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()  # "subscribed N": every channel is advertised
        if not line.startswith("subscribed"):
            raise SystemExit(f"the live client did not subscribe: {line!r}")

    def received(self) -> tuple[int, int]:
        """(messages, bytes) it got; waits for it to see the server stop."""
        out, _ = self.proc.communicate(timeout=60)
        words = [line for line in out.splitlines() if line.startswith("received")][-1].split()
        return int(words[1]), int(words[2])


def main(url: str) -> int:
    received = 0
    size = 0
    subscriptions = 0
    with connect(url, subprotocols=[SUBPROTOCOL], max_size=None, open_timeout=10) as ws:
        try:
            while True:
                frame = ws.recv()
                if isinstance(frame, str):
                    message = json.loads(frame)
                    if message.get("op") == "advertise":
                        wanted = [
                            {"id": subscriptions + n + 1, "channelId": channel["id"]}
                            for n, channel in enumerate(message["channels"])
                        ]
                        subscriptions += len(wanted)
                        ws.send(json.dumps({"op": "subscribe", "subscriptions": wanted}))
                        print(f"subscribed {subscriptions}", flush=True)
                else:
                    received += 1
                    size += len(frame)
        except ConnectionClosed:
            pass
    print(f"received {received} {size}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
