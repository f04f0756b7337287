"""Sending links for the simulator, the ground station and `send`: CAN bus, TCP, serial."""

from __future__ import annotations

import contextlib
import select
import selectors
import socket
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

from analyzer import wall_clock
from analyzer.errors import SourceError, UsageError
from analyzer.protocol.can_message import frame_from_message
from analyzer.protocol.framing import wrap_can, wrap_control
from analyzer.protocol.ids import CONTROL_ID, FEEDBACK_ID, TCP_PORT
from analyzer.protocol.types import FROM_IDU, TO_IDU, CanFrame, StreamChunk

LOOPBACK = "127.0.0.1"
DEFAULT_SERIAL_BAUD = 115200
MAX_PENDING = 256 * 1024  # bytes queued for a TCP client that does not read: then drop it
RECV_SIZE = 65536

Item = CanFrame | StreamChunk
Log = Callable[[str], None]


def _quiet(_: str) -> None:
    pass


class SimulatedLink(Protocol):
    """Both ends of the simulator speak through one of these."""

    name: str

    def receive(self, timeout: float) -> list[Item]: ...

    def send(self, can_id: int, data: bytes) -> None: ...

    def close(self) -> None: ...


# -- link specs --------------------------------------------------------------------------------


@dataclass(frozen=True)
class LinkSpec:
    """A parsed ``can:IFACE:CHANNEL[@BITRATE]``, ``tcp:[HOST:]PORT`` or ``serial:PORT[@BAUD]``."""

    kind: str  # "can", "tcp", "serial"
    interface: str = ""  # python-can interface
    channel: str = ""  # python-can channel / serial port
    host: str = LOOPBACK
    port: int = TCP_PORT
    rate: int | None = None  # CAN bitrate / serial baud rate

    def __str__(self) -> str:
        if self.kind == "can":
            rate = f"@{self.rate}" if self.rate else ""
            return f"can:{self.interface}:{self.channel}{rate}"
        if self.kind == "tcp":
            return f"tcp:{self.host}:{self.port}"
        return f"serial:{self.channel}@{self.rate or DEFAULT_SERIAL_BAUD}"


def parse_link(spec: str) -> LinkSpec:
    """Parse a link with the ``--source`` grammar (``tcp:PORT`` alone is loopback there too).

    Raises UsageError naming the accepted forms. There is no default address: a link
    that sends or listens is always named (``tcp:`` alone is refused).
    """
    from analyzer.sources.spec import CanSpec, SerialSpec, SpecError, TcpSpec, parse_source

    forms = "expected can:INTERFACE:CHANNEL[@BITRATE], tcp:HOST:PORT (or tcp:PORT on loopback) "
    forms += "or serial:PORT[@BAUD]"
    kind, _, rest = spec.partition(":")
    if kind not in ("can", "tcp", "serial") or (kind == "tcp" and not rest):
        raise UsageError(f"{spec!r}: {forms}")
    try:
        parsed = parse_source(spec)
    except SpecError as exc:
        raise UsageError(f"{spec!r}: {exc.why}; {forms}") from None
    if isinstance(parsed, CanSpec):
        return LinkSpec("can", interface=parsed.interface, channel=parsed.channel,
                        rate=parsed.bitrate)  # fmt: skip
    if isinstance(parsed, TcpSpec):
        return LinkSpec("tcp", host=parsed.host, port=parsed.port)
    assert isinstance(parsed, SerialSpec)
    return LinkSpec("serial", channel=parsed.url, rate=parsed.baudrate)


def to_stream(can_id: int, data: bytes) -> bytes:
    """A frame as it travels on TCP / UART: commands in 0x0A frames, feedback bytes as they
    are, anything else (UAV status) in a 0x0B frame with the CRC left unset (``00 00``)."""
    if can_id == CONTROL_ID:
        return wrap_control(data)
    if can_id == FEEDBACK_ID:
        return bytes(data)
    return wrap_can(can_id, data)


# -- CAN ---------------------------------------------------------------------------------------


class SimulatedCanLink:
    """A python-can bus: sends frames with extended IDs, receives every frame of the bus."""

    def __init__(self, spec: LinkSpec) -> None:
        import can

        self.name = str(spec)
        kwargs: dict[str, Any] = {"interface": spec.interface, "channel": spec.channel}
        if spec.rate:
            kwargs["bitrate"] = spec.rate
        try:
            self.bus = can.Bus(**kwargs)
        except (can.CanError, OSError, ValueError, ImportError) as exc:
            raise SourceError(f"cannot open {self.name}: {exc}") from None
        self._message = can.Message
        self._error = can.CanError
        self.send_errors = 0

    def receive(self, timeout: float) -> list[Item]:
        out: list[Item] = []
        msg = self.bus.recv(timeout=max(0.0, timeout))
        while msg is not None:
            out.append(frame_from_message(msg, self.name))
            if len(out) >= 1000:
                break
            msg = self.bus.recv(timeout=0.0)
        return out

    def send(self, can_id: int, data: bytes) -> None:
        msg = self._message(arbitration_id=can_id, data=data, is_extended_id=True)
        try:
            self.bus.send(msg, timeout=0.2)
        except self._error:
            self.send_errors += 1

    def close(self) -> None:
        self.bus.shutdown()


# -- TCP ---------------------------------------------------------------------------------------


class _Peer:
    def __init__(self, sock: socket.socket, label: str) -> None:
        self.sock = sock
        self.label = label
        self.pending = bytearray()


class TcpServerLink:
    """The IDU's side of TCP: accepts ground stations, reads their frames, sends to all."""

    def __init__(self, spec: LinkSpec, log: Log = _quiet) -> None:
        self.log = log
        try:
            self.server = socket.create_server((spec.host, spec.port))
        except OSError as exc:
            raise SourceError(f"cannot listen on {spec.host}:{spec.port}: {exc.strerror}") from None
        self.server.setblocking(False)
        host, port = self.server.getsockname()[:2]
        self.address: tuple[str, int] = (host, port)
        self.name = f"tcp:{host}:{port}"
        self.selector = selectors.DefaultSelector()
        self.selector.register(self.server, selectors.EVENT_READ)
        self.peers: dict[socket.socket, _Peer] = {}

    def receive(self, timeout: float) -> list[Item]:
        out: list[Item] = []
        for key, mask in self.selector.select(max(0.0, timeout)):
            sock: socket.socket = key.fileobj  # type: ignore[assignment]
            if sock is self.server:
                self._accept()
                continue
            peer = self.peers.get(sock)
            if peer is None:
                continue
            if mask & selectors.EVENT_WRITE:
                self._flush(peer)
            if mask & selectors.EVENT_READ and sock in self.peers:
                try:
                    data = sock.recv(RECV_SIZE)
                except (BlockingIOError, InterruptedError):
                    continue
                except OSError:
                    data = b""
                if not data:
                    self._drop(peer, "disconnected")
                    continue
                out.append(StreamChunk(wall_clock.now(), data, source=peer.label, direction=TO_IDU))
        return out

    def send(self, can_id: int, data: bytes) -> None:
        payload = to_stream(can_id, data)
        for peer in list(self.peers.values()):
            peer.pending += payload
            self._flush(peer)

    def close(self) -> None:
        for peer in list(self.peers.values()):
            self._drop(peer, "closed", quiet=True)
        self.selector.close()
        self.server.close()

    def _accept(self) -> None:
        try:
            sock, address = self.server.accept()
        except (BlockingIOError, InterruptedError):
            return
        sock.setblocking(False)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        peer = _Peer(sock, f"tcp:{address[0]}:{address[1]}")
        self.peers[sock] = peer
        self.selector.register(sock, selectors.EVENT_READ)
        self.log(f"ground station {address[0]}:{address[1]} connected")

    def _flush(self, peer: _Peer) -> None:
        if peer.pending:
            try:
                sent = peer.sock.send(peer.pending)
                del peer.pending[:sent]
            except (BlockingIOError, InterruptedError):
                pass
            except OSError:
                self._drop(peer, "connection lost")
                return
        if len(peer.pending) > MAX_PENDING:
            self._drop(peer, f"not reading ({len(peer.pending)} bytes queued)")
            return
        events = selectors.EVENT_READ | (selectors.EVENT_WRITE if peer.pending else 0)
        self.selector.modify(peer.sock, events)

    def _drop(self, peer: _Peer, why: str, quiet: bool = False) -> None:
        self.peers.pop(peer.sock, None)
        with contextlib.suppress(KeyError, ValueError):
            self.selector.unregister(peer.sock)
        peer.sock.close()
        if not quiet:
            self.log(f"ground station {peer.label.removeprefix('tcp:')} {why}")


class TcpClientLink:
    """A ground station's side of TCP: connects to the IDU (or the simulator)."""

    def __init__(self, spec: LinkSpec, connect_timeout: float = 3.0) -> None:
        self.name = str(spec)
        try:
            self.sock = socket.create_connection((spec.host, spec.port), timeout=connect_timeout)
        except OSError as exc:
            why = exc.strerror or str(exc)
            raise SourceError(f"cannot connect to {spec.host}:{spec.port}: {why}") from None
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.sock.settimeout(3.0)  # for sends; receive waits with select, so one thread may
        # receive while another sends (the socket's timeout is never changed under it)

    def receive(self, timeout: float) -> list[Item]:
        try:
            ready, _, _ = select.select([self.sock], [], [], max(0.0, timeout))
        except (OSError, ValueError) as exc:  # closed under us
            raise SourceError(f"{self.name}: {exc}") from None
        if not ready:
            return []
        try:
            data = self.sock.recv(RECV_SIZE)
        except (TimeoutError, BlockingIOError):
            return []
        except OSError as exc:
            raise SourceError(f"{self.name}: {exc.strerror or exc}") from None
        if not data:
            raise SourceError(f"{self.name}: the other side closed the connection")
        return [StreamChunk(wall_clock.now(), data, source=self.name, direction=FROM_IDU)]

    def send(self, can_id: int, data: bytes) -> None:
        try:
            self.sock.sendall(to_stream(can_id, data))
        except OSError as exc:
            raise SourceError(f"{self.name}: {exc.strerror or exc}") from None

    def close(self) -> None:
        self.sock.close()


# -- serial ------------------------------------------------------------------------------------


class SimulatedSerialLink:
    """A UART ("TTL") in the gimbal's role: the same framing as TCP."""

    def __init__(self, spec: LinkSpec, direction: str = TO_IDU) -> None:
        import serial

        self.name = str(spec)
        self.direction = direction
        try:
            self.port = serial.serial_for_url(spec.channel, baudrate=spec.rate, timeout=0)
        except (serial.SerialException, ValueError) as exc:
            raise SourceError(f"cannot open {self.name}: {exc}") from None
        self._error = serial.SerialException

    def receive(self, timeout: float) -> list[Item]:
        self.port.timeout = max(0.0, timeout)
        try:
            data = self.port.read(1)
            if data:
                self.port.timeout = 0
                data += self.port.read(RECV_SIZE)
        except self._error as exc:
            raise SourceError(f"{self.name}: {exc}") from None
        if not data:
            return []
        return [StreamChunk(wall_clock.now(), data, source=self.name, direction=self.direction)]

    def send(self, can_id: int, data: bytes) -> None:
        try:
            self.port.write(to_stream(can_id, data))
        except self._error as exc:
            raise SourceError(f"{self.name}: {exc}") from None

    def close(self) -> None:
        self.port.close()


# -- opening -----------------------------------------------------------------------------------


def open_gimbal_link(spec: LinkSpec, log: Log = _quiet) -> SimulatedLink:
    """The simulated gimbal's end: a CAN bus, a TCP server (IDU role) or a serial port."""
    if spec.kind == "can":
        return SimulatedCanLink(spec)
    if spec.kind == "tcp":
        return TcpServerLink(spec, log)
    return SimulatedSerialLink(spec, direction=TO_IDU)


def open_ground_link(spec: LinkSpec) -> SimulatedLink:
    """A ground station's end: a CAN bus, a TCP client or a serial port."""
    if spec.kind == "can":
        return SimulatedCanLink(spec)
    if spec.kind == "tcp":
        return TcpClientLink(spec)
    return SimulatedSerialLink(spec, direction=FROM_IDU)
