"""pcap / pcapng captures: TCP to or from the IDU port reassembled per flow and direction."""

from __future__ import annotations

import socket
import struct
from collections import Counter
from collections.abc import Iterator

from analyzer.errors import UsageError
from analyzer.inputs.base import InputItem, InputReader
from analyzer.inputs.pcap.notes import PcapStats, capture_notes, capture_problems
from analyzer.inputs.pcap.records import CaptureFile, Packet, PcapDamage
from analyzer.inputs.pcap.socketcan import (
    SLL2_HEADER,
    SLL_HEADER,
    CanCounts,
    can_notes,
    sll2_can,
    sll_can,
    socketcan_frame,
)
from analyzer.inputs.pcap.tcp_flows import MAX_FLOWS, MAX_PENDING_TOTAL, Flow, FlowTable, Output
from analyzer.inputs.pcap.tcp_reassembly import Delivered, Result
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
_COOKED_HEADER = {LINK_LINUX_SLL: SLL_HEADER, LINK_LINUX_SLL2: SLL2_HEADER}
ETH_VLAN = frozenset({0x8100, 0x88A8, 0x9100})
IP_TCP = 6
IPV6_SKIPPED_HEADERS = frozenset({0, 43, 60})  # hop-by-hop, routing, destination options
IPV6_FRAGMENT = 44
TCP_FIN, TCP_SYN, TCP_RST = 0x01, 0x02, 0x04


OVERSIZE_SLACK = 64  # bytes after an IP packet that padding and an FCS can explain
MAX_PORTS_SEEN = 64  # distinct other TCP ports counted for the "wrong port?" note


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
        self.port = port
        self._raw = self._open_binary()
        try:
            self._file = CaptureFile(self._raw)
            if self._file.ng:
                self.format_name = "pcapng"
                probe_link = self._probe_link()  # the first interface's link type
                self._file = CaptureFile(self._raw)
            else:
                probe_link = self._file.link
        except Exception as exc:
            self.close()
            raise UsageError(f"cannot read {path} as a capture: {_why(exc)}") from None
        self.link = probe_link if probe_link is not None else LINK_ETHERNET
        if self.link not in SUPPORTED_LINKS:
            self.close()
            raise UsageError(
                f"{path}: link type {self.link} is not supported "
                "(Ethernet, Linux cooked SLL/SLL2, raw IP, loopback, SocketCAN are)"
            )
        self._flows = FlowTable(max_flows=MAX_FLOWS, max_pending_total=MAX_PENDING_TOTAL)
        self.counts = PcapStats()
        self.can = CanCounts()
        self._other_ports: Counter[int] = Counter()  # TCP packets by the lower port number
        self._other_links: Counter[int] = Counter()  # packets of unsupported interfaces
        self._other_protocols: Counter[int] = Counter()  # neither IP nor CAN, by EtherType

    def _probe_link(self) -> int | None:
        probe = CaptureFile(self._raw)
        for _item in probe:
            break
        self._raw.seek(0)
        return probe.link

    def __iter__(self) -> Iterator[InputItem]:
        raw = self._raw
        counts = self.counts
        time = 0.0
        for record in self._file:
            if isinstance(record, PcapDamage):
                counts.damaged_records += 1
                yield diagnostic(
                    time,
                    self.source,
                    BAD_FRAME,
                    f"capture file damaged after packet {counts.packets}: {record.text}",
                    packets_read=counts.packets,
                )
                continue
            time = record.time
            counts.packets += 1
            if self.first_time is None:
                self.first_time = time
            self.last_time = time
            if not counts.packets & 0xFF:
                self.position_bytes = raw.tell()
            yield from self._packet(record)
        yield from self._results_of(self._flows.flush_all(time))
        self._collect()
        yield from capture_problems(self.counts, self.port, self.source, time)
        self.position_bytes = self.size_bytes or 0
        self._add_notes()

    def _add_notes(self) -> None:
        self.notes.extend(
            capture_notes(
                self.counts,
                self.port,
                self.source,
                self._other_ports,
                self._other_links,
                self._other_protocols if not self.can.can_frames else Counter(),
            )
        )
        self.notes.extend(can_notes(self.can))
        given_up = self._flows.given_up
        if given_up.flows or given_up.bytes:
            self.notes.append(
                f"TCP reassembly was bounded: {given_up.flows:,} connection(s) closed early "
                f"(more than {MAX_FLOWS:,} open at once) and {given_up.bytes:,} out-of-order "
                "byte(s) given up to stay within memory; see the incomplete diagnostics"
            )

    @property
    def stats(self) -> dict[str, int]:
        self._collect()
        return {**vars(self.counts), **vars(self.can), "port": self.port}

    def _collect(self) -> None:
        counts = self.counts
        totals = self._flows.totals()
        counts.flows = totals["flows"]
        counts.bytes_in = totals["bytes_in"]
        counts.bytes_delivered = totals["bytes_delivered"]
        counts.bytes_duplicate = totals["bytes_duplicate"]
        counts.bytes_missing = totals["bytes_missing"]
        counts.bytes_out_of_window = totals["bytes_out_of_window"]
        counts.flows_given_up = self._flows.given_up.flows
        counts.bytes_given_up = self._flows.given_up.bytes

    # -- layers ----------------------------------------------------------------------------

    def _packet(self, record: Packet) -> list[InputItem]:
        link = record.link
        packet = record.data
        time = record.time
        if record.fcs_bytes and not record.snapped:  # the frame check sequence is no payload
            packet = packet[: -record.fcs_bytes]
        if link == LINK_SOCKETCAN:
            return self._can(socketcan_frame(time, packet, "pcap", self.can, order="big"))
        ip: bytes | None
        if link == LINK_ETHERNET:
            ip = _ethernet_payload(packet)
        elif link == LINK_LINUX_SLL:
            sll = sll_can(packet)
            if sll is not None:  # tcpdump -i any
                return self._cooked_can(time, *sll, "any")
            ip = _cooked_ip(link, packet)
        elif link == LINK_LINUX_SLL2:
            sll2 = sll2_can(packet)
            if sll2 is not None:
                protocol, can, direction, ifindex = sll2
                return self._cooked_can(time, protocol, can, direction, f"if{ifindex}")
            ip = _cooked_ip(link, packet)
        elif link in (LINK_NULL, LINK_LOOP):
            ip = packet[4:]
        elif link in RAW_IP_LINKS:
            ip = packet
        else:  # an interface of a pcapng file with a link type we do not read
            if len(self._other_links) < MAX_PORTS_SEEN or link in self._other_links:
                self._other_links[link] += 1
            self.counts.other_packets += 1
            return []
        if not ip:
            self.counts.other_packets += 1
            kind = _link_protocol(link, packet)
            seen = self._other_protocols
            if kind is not None and (len(seen) < MAX_PORTS_SEEN or kind in seen):
                seen[kind] += 1
            return []
        return self._ip(time, ip, record.snapped)

    def _ip(self, time: float, ip: bytes, snapped: bool) -> list[InputItem]:
        counts = self.counts
        version = ip[0] >> 4
        if version == 4:
            if len(ip) < 20:
                counts.bad_packets += 1
                return []
            header = (ip[0] & 0x0F) * 4
            total = int.from_bytes(ip[2:4], "big")
            offloaded = total == 0 or (total > len(ip) and not snapped)
            if offloaded:  # TCP segmentation offload: the header was never filled in
                total = len(ip)
            elif len(ip) > total + OVERSIZE_SLACK:
                counts.oversized_packets += 1
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
            return self._tcp(time, src, dst, ip[header:total], len(ip) < total, offloaded)
        if version == 6:
            if len(ip) < 40:
                counts.bad_packets += 1
                return []
            total = 40 + int.from_bytes(ip[4:6], "big")
            offloaded = total == 40 or (total > len(ip) and not snapped)
            if offloaded:
                total = len(ip)
            elif len(ip) > total + OVERSIZE_SLACK:
                counts.oversized_packets += 1
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
            return self._tcp(time, src, dst, ip[offset:total], len(ip) < total, offloaded)
        self.counts.other_packets += 1
        return []

    def _tcp(
        self, time: float, src: str, dst: str, tcp: bytes, truncated: bool, offloaded: bool
    ) -> list[InputItem]:
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
        if offloaded and len(tcp) > offset:
            counts.offloaded_packets += 1
        out = self._flows.segment(
            (client, server),
            _flow_name(client, server),
            direction,
            seq,
            tcp[offset:],
            time,
            tcp[13],
        )
        return self._results_of(out)

    def _results_of(self, outputs: Output) -> list[InputItem]:
        out: list[InputItem] = []
        for flow, direction, results in outputs:
            if results:
                out.extend(self._results(flow, direction, results))
        return out

    def _results(self, flow: Flow, direction: str, results: list[Result]) -> list[InputItem]:
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

    def _cooked_can(
        self, time: float, protocol: int, can: bytes, direction: str, channel: str
    ) -> list[InputItem]:
        """A CAN frame of a Linux cooked capture (SLL, SLL2): the ID in host byte order."""
        frame = socketcan_frame(
            time, can, channel, self.can, order="little", protocol=protocol, direction=direction
        )
        return self._can(frame)

    def _can(self, frame: CanFrame | None) -> list[InputItem]:
        if frame is None:
            self.counts.bad_packets += 1
            return []
        return [frame]


def _ethernet_payload(packet: bytes) -> bytes | None:
    offset = 12
    ethertype = int.from_bytes(packet[offset : offset + 2], "big")
    while ethertype in ETH_VLAN and len(packet) >= offset + 6:
        offset += 4
        ethertype = int.from_bytes(packet[offset : offset + 2], "big")
    if ethertype in (ETH_IPV4, ETH_IPV6):
        return packet[offset + 2 :]
    return None


def _cooked_ip(link: int, packet: bytes) -> bytes | None:
    """The IP packet of a Linux cooked capture (SLL, SLL2) whose protocol says IP."""
    if _link_protocol(link, packet) in (ETH_IPV4, ETH_IPV6):
        return packet[_COOKED_HEADER[link] :]
    return None


def _link_protocol(link: int, packet: bytes) -> int | None:
    """The EtherType / protocol of an Ethernet or Linux cooked packet (None for others)."""
    where = {LINK_ETHERNET: 12, LINK_LINUX_SLL: 14, LINK_LINUX_SLL2: 0}.get(link)
    if where is None or len(packet) < where + 2:
        return None
    return int.from_bytes(packet[where : where + 2], "big")


def _flow_name(client: tuple[str, int], server: tuple[str, int]) -> str:
    return f"tcp:{client[0]}:{client[1]}-{server[0]}:{server[1]}"


def _why(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else "not a pcap or pcapng file"
