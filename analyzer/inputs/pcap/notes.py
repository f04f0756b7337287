"""What a pcap reader tells the user after reading: counters, notes and capture problems."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

from analyzer.protocol.types import BAD_FRAME, INCOMPLETE, Event, diagnostic


@dataclass
class PcapStats:
    packets: int = 0
    tcp_packets: int = 0  # TCP segments to or from the port
    other_packets: int = 0  # not IP/TCP, or another port
    bad_packets: int = 0  # too short or malformed headers
    truncated_packets: int = 0  # segments of the port captured shorter than sent
    fragments: int = 0  # IP fragments (not reassembled)
    damaged_records: int = 0  # damage in the file itself (record headers, blocks)
    offloaded_packets: int = 0  # IP total length 0 or over the packet (TCP offload)
    oversized_packets: int = 0  # far more bytes than their IP packet: a wrong record length?
    flows: int = 0
    flows_given_up: int = 0  # connections closed early to stay within MAX_FLOWS
    bytes_given_up: int = 0  # out-of-order bytes handed on past holes to bound memory
    bytes_in: int = 0
    bytes_delivered: int = 0
    bytes_duplicate: int = 0
    bytes_missing: int = 0
    bytes_out_of_window: int = 0


def capture_notes(
    counts: PcapStats,
    port: int,
    source: str,
    other_ports: Counter[int],
    other_links: Counter[int],
    other_protocols: Counter[int],
) -> list[str]:
    """Facts about a capture worth saying: wrong port, TCP offload, unsupported interfaces,
    and what a capture without TCP or CAN traffic holds instead (``other_protocols``)."""
    notes: list[str] = []
    if not counts.tcp_packets and not other_ports and other_protocols:
        seen = ", ".join(f"0x{p:04X} ({n} packets)" for p, n in other_protocols.most_common(5))
        notes.append(
            f"no TCP or CAN traffic in {source}; link-layer protocols seen: {seen} "
            "(0x000C is CAN, 0x000D CAN FD, 0x000E CAN XL)"
        )
    if not counts.tcp_packets and other_ports:
        seen = ", ".join(f"{p} ({n} packets)" for p, n in other_ports.most_common(5))
        notes.append(
            f"no TCP traffic to or from port {port} in {source}; "
            f"TCP ports seen: {seen}. Give the IDU's port with --port."
        )
    if counts.offloaded_packets:
        notes.append(
            f"{counts.offloaded_packets:,} IP packet(s) of port {port} had a total "
            "length of 0 or larger than the packet, as a capture on the sending host with "
            "TCP segmentation offload records them: read with the captured length, as "
            "Wireshark does"
        )
    if other_links:
        links = ", ".join(str(link) for link in sorted(other_links))
        notes.append(
            f"{sum(other_links.values()):,} packet(s) of interfaces with an "
            f"unsupported link type ({links}) were skipped"
        )
    return notes


def capture_problems(counts: PcapStats, port: int, source: str, time: float) -> list[Event]:
    """Diagnostics for what went wrong in capturing: cut segments, wrong lengths, bad packets."""
    out: list[Event] = []
    if counts.truncated_packets:
        out.append(
            diagnostic(
                time,
                source,
                INCOMPLETE,
                f"{counts.truncated_packets} TCP segment(s) of port {port} were captured "
                "shorter than sent (snap length or a cut-off file): bytes are missing",
                packets=counts.truncated_packets,
            )
        )
    if counts.oversized_packets:
        out.append(
            diagnostic(
                time,
                source,
                BAD_FRAME,
                f"{counts.oversized_packets} packet record(s) hold far more bytes than their "
                "IP packet: their captured length may be wrong, and packets that follow "
                "them in the file may be hidden inside them",
                packets=counts.oversized_packets,
            )
        )
    if counts.bytes_out_of_window:
        out.append(
            diagnostic(
                time,
                source,
                BAD_FRAME,
                f"{counts.bytes_out_of_window:,} byte(s) of TCP segments of port {port} lay "
                "before their connection's SYN or far beyond its window (a damaged sequence "
                "number, or packets of another connection): they were not decoded",
                byte_count=counts.bytes_out_of_window,
            )
        )
    if counts.bad_packets:
        out.append(
            diagnostic(
                time,
                source,
                BAD_FRAME,
                f"{counts.bad_packets} packet(s) too short or malformed to read",
                packets=counts.bad_packets,
            )
        )
    return out
