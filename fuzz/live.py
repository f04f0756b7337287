"""Targets of a live TCP link: what the IDU (``tcp:``) or both peers of a proxy send.

Each input runs a capture wired as ``record`` wires it (``open_live_recording``: the
recording, the analysis, the link watch) plus the monitor's screen model
(``MonitorState``), on 127.0.0.1 only: a peer thread sends the input's bytes and
closes. The capture must see the link close, the proxy must forward every byte
unchanged both ways, and the recording it wrote must read back.
"""

from __future__ import annotations

import socket
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

from fuzz.files import scratch
from fuzz.rules import Crash, cli

WAIT_S = 3.0  # a capture that has not seen the link close by then is stuck
BATCH_S = 0.005  # the capture's batch interval (record's is 0.05: here 10 times faster)
LOCALHOST = "127.0.0.1"


class _Watch:
    """A sink: the monitor's screen model folds every batch; ``ended`` is set when the
    link is lost (the peer closed)."""

    def __init__(self) -> None:
        from analyzer.tui.state import MonitorState

        self.state = MonitorState()
        self.ended = threading.Event()

    def handle(self, batch: Any) -> None:
        self.state.fold(batch)
        for event in batch.events:
            if event.fields.get("kind") == "link" and event.fields.get("state") == "lost":
                self.ended.set()

    def close(self) -> None:
        self.state.source_finished()


def _listener() -> socket.socket:
    server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    server.bind((LOCALHOST, 0))
    server.listen(1)
    server.settimeout(WAIT_S)
    return server


def _exchange(sock: socket.socket, send: bytes, expect: int, got: list[bytes]) -> None:
    """Send ``send``, then take what comes until ``expect`` bytes or the end."""
    sock.settimeout(WAIT_S)
    try:
        sock.sendall(send)
        received = bytearray()
        while len(received) < expect:
            piece = sock.recv(65536)
            if not piece:
                break
            received += piece
        got.append(bytes(received))
    except OSError as exc:
        got.append(f"{type(exc).__name__}: {exc}".encode())


def _serve_once(server: socket.socket, send: bytes, expect: int, got: list[bytes]) -> None:
    """Accept one connection, exchange, close: the IDU's side."""
    try:
        conn, _ = server.accept()
    except OSError as exc:
        got.append(f"no connection: {exc}".encode())
        return
    with conn:
        _exchange(conn, send, expect, got)
        if expect == 0:  # the client target: the IDU closes after sending
            conn.shutdown(socket.SHUT_RDWR)


def _capture(spec: str, source: Any, path: Path, peers: Callable[[], None], sent: int) -> None:
    """Run ``source`` into a recording as ``record`` does, with ``peers`` talking to it,
    until the link is lost: the capture must have taken every one of the ``sent`` bytes,
    and the recording must read back."""
    from analyzer.cli import build_parser
    from analyzer.commands.live_recording import open_live_recording
    from analyzer.mcapio.write.sink import recording_metadata

    args = build_parser("record").parse_args(
        ["record", "--source", spec, "-o", str(path), "-q", "-f"]
    )
    recording = open_live_recording(
        args, source, str(path), metadata=recording_metadata(spec), hold_back=0.0
    )
    capture = recording.capture
    capture.batch_interval = BATCH_S
    watch = _Watch()
    capture.add_sink(watch)
    capture.start()
    try:
        peers()
        ended = watch.ended.wait(WAIT_S)
    finally:
        capture.stop()
        capture.join()
        recording.source.close()
        recording.sink.close()
    if capture.error is not None:
        raise Crash(f"the capture failed: {capture.error}")
    if not ended:
        raise Crash(f"the capture of {spec} did not see the peer close in {WAIT_S} s")
    taken = capture.stats.bytes
    if taken != sent:
        raise Crash(f"the capture of {spec} took {taken:,} of the {sent:,} bytes sent")
    _read_back(path)


def _read_back(path: Path) -> None:
    """A recording this tool wrote reads back: as recorded and decoded again."""
    from analyzer.api.reading import read
    from analyzer.api.recording import Recording

    list(Recording(path).events())
    list(read(path))
    if cli(["info", str(path)]) != 0:
        raise Crash(f"info refused the recording {path} the capture wrote")


def run_client(data: bytes) -> None:
    """``record --source tcp:``: the IDU sends ``data`` and closes the connection."""
    from analyzer.sources import open_source

    server = _listener()
    got: list[bytes] = []
    spec = f"tcp:{LOCALHOST}:{server.getsockname()[1]}"
    idu = threading.Thread(target=_serve_once, args=(server, data, 0, got), daemon=True)
    try:
        source = open_source(spec)
        idu.start()
        _capture(spec, source, scratch() / "tcp.mcap", lambda: idu.join(WAIT_S), len(data))
    finally:
        server.close()


def split(data: bytes) -> tuple[bytes, bytes]:
    """A proxy input: 2 bytes that say how much of the rest the ground station sends;
    the IDU sends the other part."""
    if len(data) < 2:
        return b"", data
    rest = data[2:]
    cut = int.from_bytes(data[:2], "little") % (len(rest) + 1)
    return rest[:cut], rest[cut:]


def run_proxy(data: bytes) -> None:
    """``record --source proxy:``: ground station and IDU send their parts at once; each
    must receive the other's bytes unchanged; then the ground station leaves."""
    from analyzer.sources import open_source

    to_idu, to_gs = split(data)
    server = _listener()
    at_idu: list[bytes] = []
    at_gs: list[bytes] = []
    idu_spec = f"{LOCALHOST}:{server.getsockname()[1]}"
    source = open_source(f"proxy:{LOCALHOST}:0->{idu_spec}")
    host, port = source.listen_address  # type: ignore[attr-defined]
    spec = f"proxy:{host}:{port}->{idu_spec}"
    idu = threading.Thread(
        target=_serve_once, args=(server, to_gs, len(to_idu), at_idu), daemon=True
    )

    def ground_station() -> None:
        idu.start()
        try:
            with socket.create_connection((host, port), WAIT_S) as gs:
                _exchange(gs, to_idu, len(to_gs), at_gs)
                idu.join(WAIT_S)
        except OSError as exc:
            at_gs.append(f"{type(exc).__name__}: {exc}".encode())

    try:
        _capture(spec, source, scratch() / "proxy.mcap", ground_station, len(data[2:]))
    finally:
        server.close()
    if at_idu != [to_idu] or at_gs != [to_gs]:
        raise Crash(
            f"the proxy did not forward the bytes unchanged: the IDU got {at_idu!r:.200} of "
            f"{to_idu!r:.200}, the ground station {at_gs!r:.200} of {to_gs!r:.200}"
        )


def _sample_directions() -> tuple[bytes, bytes]:
    """The TCP sample's two directions: (ground station -> IDU, IDU -> ground station)."""
    from analyzer.inputs import open_input
    from analyzer.protocol.types import FROM_IDU, TO_IDU, StreamChunk
    from fuzz.seeds import SAMPLES

    sent = {TO_IDU: bytearray(), FROM_IDU: bytearray()}
    reader = open_input(str(SAMPLES / "idu-tcp.pcap"), "pcap")
    try:
        for item in reader:
            if isinstance(item, StreamChunk) and item.direction in sent:
                sent[item.direction] += item.data
    finally:
        reader.close()
    return bytes(sent[TO_IDU]), bytes(sent[FROM_IDU])


def seeds_client() -> list[bytes]:
    """What the IDU sent in the TCP sample; the UART sample."""
    from fuzz.seeds import SAMPLES

    return [_sample_directions()[1], (SAMPLES / "uart-dump.bin").read_bytes()]


def seeds_proxy() -> list[bytes]:
    """Both directions of the TCP sample, whole and their first frames."""
    to_idu, to_gs = _sample_directions()
    return [
        len(to_idu).to_bytes(2, "little") + to_idu + to_gs,
        (64).to_bytes(2, "little") + to_idu[:64] + to_gs[:256],
    ]
