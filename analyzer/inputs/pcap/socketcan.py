"""SocketCAN frames in captures: LINKTYPE_CAN_SOCKETCAN and CAN inside Linux cooked SLL / SLL2.

``tcpdump -i any`` on a host with a CAN interface writes LINUX_SLL (113) or LINUX_SLL2
(276) records whose protocol is 0x000C (CAN) or 0x000D (CAN FD), followed by the
kernel's ``struct can_frame`` / ``struct canfd_frame`` with the CAN ID in the host's
byte order; LINKTYPE_CAN_SOCKETCAN (227) has it in network byte order (libpcap's
pcap-common.c, sll.h; linux/can.h). Whichever order the file should have, an ID that
makes no sense in it but does in the other is read the other way round.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from analyzer.protocol.types import CanFrame

ETH_P_CAN, ETH_P_CANFD, ETH_P_CANXL = 0x000C, 0x000D, 0x000E
CAN_PROTOCOLS = frozenset({ETH_P_CAN, ETH_P_CANFD})
CAN_EFF_FLAG, CAN_RTR_FLAG, CAN_ERR_FLAG = 0x80000000, 0x40000000, 0x20000000
CANFD_FDF = 0x04  # canfd_frame.flags: a CAN FD frame
CAN_HEADER = 8  # can_id (4), len, flags / pad, two reserved bytes
CAN_MTU, CANFD_MTU = 16, 72
SLL_HEADER, SLL2_HEADER = 16, 20
PACKET_OUTGOING = 4  # sll_pkttype of a frame the host sent


@dataclass
class CanCounts:
    can_frames: int = 0
    fd_frames: int = 0  # CAN FD frames (any length)
    long_fd_frames: int = 0  # CAN FD frames with more than 8 data bytes
    swapped_can_ids: int = 0  # IDs read in the other byte order than the link type says
    truncated_can_frames: int = 0  # fewer data bytes captured than the frame's length


def plausible_can_id(raw_id: int) -> bool:
    """Whether a SocketCAN ID word makes sense: 11 bits unless extended, small error classes."""
    ident = raw_id & 0x1FFFFFFF
    if raw_id & CAN_ERR_FLAG:
        return ident < 0x1000
    return bool(raw_id & CAN_EFF_FLAG) or ident <= 0x7FF


def sll_can(packet: bytes) -> tuple[int, bytes, str] | None:
    """(protocol, SocketCAN frame, direction) of a LINUX_SLL record carrying CAN, else None."""
    if len(packet) < SLL_HEADER or int.from_bytes(packet[14:16], "big") not in CAN_PROTOCOLS:
        return None
    outgoing = int.from_bytes(packet[0:2], "big") == PACKET_OUTGOING
    return int.from_bytes(packet[14:16], "big"), packet[SLL_HEADER:], "tx" if outgoing else "rx"


def sll2_can(packet: bytes) -> tuple[int, bytes, str, int] | None:
    """(protocol, frame, direction, interface index) of a LINUX_SLL2 record carrying CAN."""
    if len(packet) < SLL2_HEADER or int.from_bytes(packet[0:2], "big") not in CAN_PROTOCOLS:
        return None
    outgoing = packet[10] == PACKET_OUTGOING
    return (
        int.from_bytes(packet[0:2], "big"),
        packet[SLL2_HEADER:],
        "tx" if outgoing else "rx",
        int.from_bytes(packet[4:8], "big"),
    )


def socketcan_frame(
    time: float,
    packet: bytes,
    channel: str,
    counts: CanCounts,
    *,
    order: Literal["big", "little"],
    protocol: int | None = None,
    direction: str = "",
) -> CanFrame | None:
    """A CanFrame from a ``can_frame`` / ``canfd_frame``; None when too short to read.

    ``order`` is the byte order the link type gives the ID ("big" or "little");
    ``protocol`` the SLL protocol when known (0x000D marks CAN FD).
    """
    if len(packet) < CAN_HEADER:
        return None
    other: Literal["big", "little"] = "little" if order == "big" else "big"
    raw_id = int.from_bytes(packet[0:4], order)
    if not plausible_can_id(raw_id):
        swapped = int.from_bytes(packet[0:4], other)
        if plausible_can_id(swapped):
            raw_id = swapped
            counts.swapped_can_ids += 1
    length = packet[4]
    is_fd = (
        protocol == ETH_P_CANFD
        or len(packet) > CAN_MTU
        or (protocol is None and bool(packet[5] & CANFD_FDF))
    )
    data = packet[CAN_HEADER : CAN_HEADER + length]
    if len(data) < length:
        counts.truncated_can_frames += 1
    counts.can_frames += 1
    if is_fd:
        counts.fd_frames += 1
        if length > 8:
            counts.long_fd_frames += 1
    remote = bool(raw_id & CAN_RTR_FLAG) and not is_fd
    return CanFrame(
        time,
        raw_id & 0x1FFFFFFF,
        b"" if remote else data,
        bool(raw_id & CAN_EFF_FLAG),
        channel,
        remote,
        bool(raw_id & CAN_ERR_FLAG),
        is_fd,
        direction,
        length if remote else 0,
    )


def can_notes(can: CanCounts) -> list[str]:
    """Notes for the user about the CAN frames of a capture."""
    notes: list[str] = []
    if can.swapped_can_ids:
        notes.append(
            f"{can.swapped_can_ids:,} SocketCAN frame(s) had their CAN ID in the other byte "
            "order than their link type gives it (little-endian in a SocketCAN capture, as an "
            "old libpcap on a little-endian host wrote it; big-endian in a Linux cooked "
            "capture, from a big-endian host): read byte-swapped"
        )
    if can.long_fd_frames:
        notes.append(
            f"{can.long_fd_frames:,} of {can.fd_frames:,} CAN FD frame(s) carry more than 8 "
            "data bytes; the protocol uses classic CAN, so they are handed on as other traffic "
            "(--raw shows them)"
        )
    if can.truncated_can_frames:
        notes.append(
            f"{can.truncated_can_frames:,} CAN frame(s) were captured shorter than their length"
        )
    return notes
