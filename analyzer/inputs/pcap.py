"""pcap / pcapng captures: TCP to or from the IDU port reassembled per flow and direction."""

from __future__ import annotations

import socket
import struct
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from analyzer.errors import UsageError
from analyzer.inputs.base import InputItem, InputReader
from analyzer.inputs.tcp_reassembly import Delivered, Result, TcpDirection
from analyzer.protocol.ids import TCP_PORT
from analyzer.protocol.types import (
    BAD_FRAME,
    FROM_IDU,
    INCOMPLETE,
    TO_IDU,
    CanFrame,
    StreamChunk,
    diagnostic,
)

# Link-layer types of the capture file (LINKTYPE_* of libpcap).
LINK_NULL = 0
LINK_ETHERNET = 1
LINK_RAW = 101
LINK_LOOP = 108
LINK_LINUX_SLL = 113
LINK_SOCKETCAN = 227
LINK_IPV4 = 228
LINK_IPV6 = 229
LINK_LINUX_SLL2 = 276
RAW_IP_LINKS = frozenset({LINK_RAW, 12, 14, LINK_IPV4, LINK_IPV6})
SUPPORTED_LINKS = frozenset(
    {LINK_NULL, LINK_ETHERNET, LINK_LOOP, LINK_LINUX_SLL, LINK_LINUX_SLL2, LINK_SOCKETCAN}
    | RAW_IP_LINKS
)

ETH_IPV4 = 0x0800
ETH_IPV6 = 0x86DD
ETH_VLAN = frozenset({0x8100, 0x88A8, 0x9100})
IP_TCP = 6
IPV6_SKIPPED_HEADERS = frozenset({0, 43, 60})  # hop-by-hop, routing, destination options
IPV6_FRAGMENT = 44
TCP_FIN, TCP_SYN, TCP_RST = 0x01, 0x02, 0x04

CAN_EFF_FLAG, CAN_RTR_FLAG, CAN_ERR_FLAG = 0x80000000, 0x40000000, 0x20000000
CANFD_FDF = 0x04
CAN_HEADER = 8  # id (4, big-endian in captures), length, flags, 2 reserved

PCAP_MAGICS = (b"\xd4\xc3\xb2\xa1", b"\xa1\xb2\xc3\xd4", b"\x4d\x3c\xb2\xa1", b"\xa1\xb2\x3c\x4d")
PCAPNG_MAGIC = b"\x0a\x0d\x0d\x0a"


@dataclass
class _Flow:
    """Both directions of one TCP connection with the IDU port."""

    source: str
    directions: dict[str, TcpDirection] = field(default_factory=dict)

    def direction(self, name: str) -> TcpDirection:
        state = self.directions.get(name)
        if state is None:
            state = self.directions[name] = TcpDirection()
        return state


MAX_PORTS_SEEN = 64  # distinct other TCP ports counted for the "wrong port?" note


@dataclass
class PcapStats:
    packets: int = 0
    tcp_packets: int = 0  # TCP segments to or from the port
    other_packets: int = 0  # not IP/TCP, or another port
    bad_packets: int = 0  # too short or malformed headers
    truncated_packets: int = 0  # segments of the port captured shorter than sent
    fragments: int = 0  # IP fragments (not reassembled)
    can_frames: int = 0  # SocketCAN captures
    flows: int = 0
    bytes_in: int = 0
    bytes_delivered: int = 0
    bytes_duplicate: int = 0
    bytes_missing: int = 0
    bytes_out_of_window: int = 0


class PcapReader(InputReader):
    """TCP streams to/from ``port`` (the IDU's 2000) of a pcap or pcapng file.

    Ethernet (VLAN tags too), Linux cooked (SLL, SLL2), raw IP and loopback captures
    are understood; each flow and direction is reassembled (out-of-order, retransmitted
    and overlapping segments) and handed on as StreamChunks whose ``source`` names the
    flow and whose ``direction`` is ``gs_to_idu`` towards the port, ``idu_to_gs`` from
    it. SocketCAN captures (Wireshark on ``can0``) give CanFrames.
    """

    format_name = "pcap"

    def __init__(self, path: str, *, port: int = TCP_PORT) -> None:
        super().__init__(path)
        import dpkt

        self.port = port
        self._raw = self._open_binary()
        magic = self._raw.read(4)
        self._raw.seek(0)
        try:
            if magic == PCAPNG_MAGIC:
                self._reader: Any = dpkt.pcapng.Reader(self._raw)
                self.format_name = "pcapng"
            elif magic in PCAP_MAGICS:
                self._reader = dpkt.pcap.Reader(self._raw)
            else:
                raise ValueError("not a pcap or pcapng file")
        except Exception as exc:
            self.close()
            raise UsageError(f"cannot read {path} as a capture: {_why(exc)}") from None
        self.link = int(self._reader.datalink())
        if self.link not in SUPPORTED_LINKS:
            self.close()
            raise UsageError(
                f"{path}: link type {self.link} is not supported "
                "(Ethernet, Linux cooked SLL/SLL2, raw IP, loopback, SocketCAN are)"
            )
        self._flows: dict[tuple[Any, ...], _Flow] = {}
        self.counts = PcapStats()
        self._other_ports: Counter[int] = Counter()  # TCP packets by the lower port number

    def __iter__(self) -> Iterator[InputItem]:
        raw = self._raw
        counts = self.counts
        time = 0.0
        try:
            for ts, packet in self._reader:
                time = float(ts)
                counts.packets += 1
                if self.first_time is None:
                    self.first_time = time
                self.last_time = time
                if not counts.packets & 0xFF:
                    self.position_bytes = raw.tell()
                yield from self._packet(time, packet)
        except Exception as exc:  # a damaged or cut-off capture file
            yield diagnostic(
                time,
                self.source,
                BAD_FRAME,
                f"reading the capture stopped after packet {counts.packets}: {_why(exc)}",
                packets_read=counts.packets,
            )
        for flow in self._flows.values():
            for name, state in flow.directions.items():
                yield from self._results(flow, name, state.flush(time))
        self._collect()
        yield from self._capture_problems(time)
        self.position_bytes = self.size_bytes or 0
        if not counts.tcp_packets and self._other_ports:
            seen = ", ".join(
                f"{port} ({n} packets)" for port, n in self._other_ports.most_common(5)
            )
            self.notes.append(
                f"no TCP traffic to or from port {self.port} in {self.source}; "
                f"TCP ports seen: {seen}. Give the IDU's port with --port."
            )

    def _capture_problems(self, time: float) -> list[InputItem]:
        counts = self.counts
        out: list[InputItem] = []
        if counts.truncated_packets:
            out.append(
                diagnostic(
                    time,
                    self.source,
                    INCOMPLETE,
                    f"{counts.truncated_packets} TCP segment(s) of port {self.port} were captured "
                    "shorter than sent (snap length or a cut-off file): bytes are missing",
                    packets=counts.truncated_packets,
                )
            )
        if counts.bad_packets:
            out.append(
                diagnostic(
                    time,
                    self.source,
                    BAD_FRAME,
                    f"{counts.bad_packets} packet(s) too short or malformed to read",
                    packets=counts.bad_packets,
                )
            )
        return out

    @property
    def stats(self) -> dict[str, int]:
        self._collect()
        return dict(vars(self.counts))

    def _collect(self) -> None:
        counts = self.counts
        states = [s for f in self._flows.values() for s in f.directions.values()]
        counts.flows = len(self._flows)
        counts.bytes_in = sum(s.bytes_in for s in states)
        counts.bytes_delivered = sum(s.bytes_delivered for s in states)
        counts.bytes_duplicate = sum(s.bytes_duplicate for s in states)
        counts.bytes_missing = sum(s.bytes_missing for s in states)
        counts.bytes_out_of_window = sum(s.bytes_out_of_window for s in states)

    # -- layers ----------------------------------------------------------------------------

    def _packet(self, time: float, packet: bytes) -> list[InputItem]:
        link = self.link
        if link == LINK_SOCKETCAN:
            return self._can(time, packet)
        ip: bytes | None
        if link == LINK_ETHERNET:
            ip = _ethernet_payload(packet)
        elif link == LINK_LINUX_SLL:
            ip = packet[16:] if packet[14:16] in (b"\x08\x00", b"\x86\xdd") else None
        elif link == LINK_LINUX_SLL2:
            ip = packet[20:] if packet[0:2] in (b"\x08\x00", b"\x86\xdd") else None
        elif link in (LINK_NULL, LINK_LOOP):
            ip = packet[4:]
        else:
            ip = packet
        if not ip:
            self.counts.other_packets += 1
            return []
        return self._ip(time, ip)

    def _ip(self, time: float, ip: bytes) -> list[InputItem]:
        counts = self.counts
        version = ip[0] >> 4
        if version == 4:
            if len(ip) < 20:
                counts.bad_packets += 1
                return []
            header = (ip[0] & 0x0F) * 4
            total = int.from_bytes(ip[2:4], "big")
            if header < 20 or total < header:
                counts.bad_packets += 1
                return []
            if ip[9] != IP_TCP:
                counts.other_packets += 1
                return []
            if int.from_bytes(ip[6:8], "big") & 0x3FFF:  # more fragments / fragment offset
                counts.fragments += 1
                return []
            src = socket.inet_ntop(socket.AF_INET, ip[12:16])
            dst = socket.inet_ntop(socket.AF_INET, ip[16:20])
            return self._tcp(time, src, dst, ip[header:total], len(ip) < total)
        if version == 6:
            if len(ip) < 40:
                counts.bad_packets += 1
                return []
            total = 40 + int.from_bytes(ip[4:6], "big")
            nxt, offset = ip[6], 40
            while nxt in IPV6_SKIPPED_HEADERS and len(ip) >= offset + 8:
                nxt, offset = ip[offset], offset + (ip[offset + 1] + 1) * 8
            if nxt == IPV6_FRAGMENT:
                counts.fragments += 1
                return []
            if nxt != IP_TCP:
                counts.other_packets += 1
                return []
            src = "[" + socket.inet_ntop(socket.AF_INET6, ip[8:24]) + "]"
            dst = "[" + socket.inet_ntop(socket.AF_INET6, ip[24:40]) + "]"
            return self._tcp(time, src, dst, ip[offset:total], len(ip) < total)
        self.counts.other_packets += 1
        return []

    def _tcp(self, time: float, src: str, dst: str, tcp: bytes, truncated: bool) -> list[InputItem]:
        counts = self.counts
        if len(tcp) < 20:
            counts.bad_packets += 1
            return []
        sport, dport, seq = struct.unpack_from(">HHI", tcp)
        if dport == self.port:
            direction, client, server = TO_IDU, (src, sport), (dst, dport)
        elif sport == self.port:
            direction, client, server = FROM_IDU, (dst, dport), (src, sport)
        else:
            counts.other_packets += 1
            if len(self._other_ports) < MAX_PORTS_SEEN or min(sport, dport) in self._other_ports:
                self._other_ports[min(sport, dport)] += 1
            return []
        offset = (tcp[12] >> 4) * 4
        if offset < 20:
            counts.bad_packets += 1
            return []
        counts.tcp_packets += 1
        if truncated:
            counts.truncated_packets += 1
        flags = tcp[13]
        key = (client, server)
        flow = self._flows.get(key)
        out: list[InputItem] = []
        if flow is None or (flags & TCP_SYN and _new_connection(flow, direction, seq)):
            if flow is not None:  # the same ports reused by a new connection
                for name, state in flow.directions.items():
                    out.extend(self._results(flow, name, state.flush(time)))
                generation = flow.source.rsplit("#", 1)
                number = int(generation[1]) + 1 if len(generation) == 2 else 2
                name = f"{_flow_name(client, server)}#{number}"
            else:
                name = _flow_name(client, server)
            flow = self._flows[key] = _Flow(name)
        state = flow.direction(direction)
        payload = tcp[offset:]
        out.extend(
            self._results(flow, direction, state.segment(seq, payload, time, syn=bool(flags & 2)))
        )
        if flags & TCP_FIN:
            state.fin_seen = True
        if flags & TCP_RST:
            for name, each in flow.directions.items():
                out.extend(self._results(flow, name, each.flush(time)))
        return out

    def _results(self, flow: _Flow, direction: str, results: list[Result]) -> list[InputItem]:
        out: list[InputItem] = []
        for result in results:
            if isinstance(result, Delivered):
                out.append(StreamChunk(result.time, result.data, flow.source, direction))
            else:
                out.append(
                    diagnostic(
                        result.time,
                        flow.source,
                        INCOMPLETE,
                        f"{result.size} byte(s) of the TCP stream missing from the capture "
                        f"at stream offset {result.offset} (segment never captured)",
                        direction=direction,
                        missing_bytes=result.size,
                    )
                )
        return out

    def _can(self, time: float, packet: bytes) -> list[InputItem]:
        if len(packet) < CAN_HEADER:
            self.counts.bad_packets += 1
            return []
        raw_id = int.from_bytes(packet[0:4], "big")
        length = packet[4]
        data = packet[CAN_HEADER : CAN_HEADER + length]
        if len(data) < length:
            self.counts.truncated_packets += 1
        self.counts.can_frames += 1
        is_fd = len(packet) > 16 or bool(packet[5] & CANFD_FDF)
        remote = bool(raw_id & CAN_RTR_FLAG)
        return [
            CanFrame(
                time,
                raw_id & 0x1FFFFFFF,
                b"" if remote else data,
                bool(raw_id & CAN_EFF_FLAG),
                "pcap",
                remote,
                bool(raw_id & CAN_ERR_FLAG),
                is_fd,
            )
        ]


def _ethernet_payload(packet: bytes) -> bytes | None:
    offset = 12
    ethertype = int.from_bytes(packet[offset : offset + 2], "big")
    while ethertype in ETH_VLAN and len(packet) >= offset + 6:
        offset += 4
        ethertype = int.from_bytes(packet[offset : offset + 2], "big")
    if ethertype in (ETH_IPV4, ETH_IPV6):
        return packet[offset + 2 :]
    return None


def _new_connection(flow: _Flow, direction: str, seq: int) -> bool:
    """A SYN whose sequence number does not fit the connection seen so far."""
    state = flow.directions.get(direction)
    if state is None or state.base is None:
        return False
    return (seq + 1) % (1 << 32) != state.base


def _flow_name(client: tuple[str, int], server: tuple[str, int]) -> str:
    return f"tcp:{client[0]}:{client[1]}-{server[0]}:{server[1]}"


def _why(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0]}" if text else type(exc).__name__
