"""CAN in captures: `tcpdump -i any` (Linux cooked SLL / SLL2) and CAN FD in SocketCAN pcaps.

The SLL files are made as tcpdump writes them on a host with can0 (tests/log_makers.py)
and hold the 629 frames of samples/flight-candump.log; where tshark is installed it
reads the same files, as the user's other tool would.
"""

from __future__ import annotations

import os
import shutil
import struct
import subprocess
from pathlib import Path

import dpkt
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from analyzer.inputs import InputReader, open_input
from analyzer.protocol.codec import encode_command
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.types import TOPIC_COMMAND, CanFrame, Event
from tests.log_makers import flight_frames, sll_pcap, socketcan_frame

FRAMES = flight_frames()
LINKS = {113: "any", 276: "if5"}  # the channel each link type gives the frames


def read(path: Path) -> tuple[list[CanFrame], list[Event], InputReader]:
    reader = open_input(str(path))
    with reader:
        items = list(reader)
    frames = [i for i in items if isinstance(i, CanFrame)]
    return frames, [i for i in items if isinstance(i, Event)], reader


@pytest.mark.parametrize("ng", [False, True])
@pytest.mark.parametrize("link", sorted(LINKS))
def test_tcpdump_any_capture_gives_exactly_the_frames(tmp_path: Path, link: int, ng: bool) -> None:
    path = sll_pcap(tmp_path / "any.pcap", FRAMES, link, ng=ng)
    frames, events, reader = read(path)
    assert events == []
    assert [(f.can_id, f.data, f.extended) for f in frames] == [
        (f.can_id, f.data, f.extended) for f in FRAMES
    ]
    assert all(
        a.time == pytest.approx(b.time, abs=1e-6) for a, b in zip(frames, FRAMES, strict=True)
    )
    assert {(f.channel, f.direction, f.is_fd) for f in frames} == {(LINKS[link], "rx", False)}
    assert reader.stats["can_frames"] == 629
    assert reader.notes == []


@pytest.mark.skipif(
    shutil.which("tshark") is None and os.environ.get("GIMBAL_REQUIRE_TSHARK") != "1",
    reason="tshark is not installed (Debian package tshark)",
)
@pytest.mark.parametrize("link", sorted(LINKS))
def test_tshark_reads_the_same_frames(tmp_path: Path, link: int) -> None:
    path = sll_pcap(tmp_path / "any.pcap", FRAMES[:50], link)
    done = subprocess.run(
        ["tshark", "-r", str(path), "-T", "fields", "-e", "can.id", "-e", "can.len", "-e", "data.data"],
        capture_output=True, text=True, timeout=60, check=True, encoding="utf-8",
    )  # fmt: skip
    rows = [line.split("\t") for line in done.stdout.splitlines()]
    frames, _, _ = read(path)
    assert [(int(r[0]), bytes.fromhex(r[2])[: int(r[1])]) for r in rows] == [
        (f.can_id, f.data) for f in frames
    ]


def test_frames_the_host_sent_are_tx(tmp_path: Path) -> None:
    path = tmp_path / "sent.pcap"
    frame = CanFrame(1.0, 0xF01, encode_command("look_down"), True)
    with path.open("wb") as handle:
        writer = dpkt.pcap.Writer(handle, linktype=276)
        header = struct.pack(">HHIHBB8s", 0x000C, 0, 3, 280, 4, 0, b"")  # PACKET_OUTGOING
        writer.writepkt(header + socketcan_frame(frame), ts=1.0)
    frames, _, _ = read(path)
    assert [(f.direction, f.channel) for f in frames] == [("tx", "if3")]
    events = ProtocolDecoder().feed(frames[0])
    assert [e.topic for e in events] == [TOPIC_COMMAND]


def canfd_frame(can_id: int, data: bytes, order: str = ">") -> bytes:
    """struct canfd_frame: id, len, flags (CANFD_FDF), two reserved bytes, 64 data bytes."""
    return struct.pack(order + "IBBBB", can_id, len(data), 0x04, 0, 0) + data.ljust(64, b"\0")


def test_can_fd_frames_of_classic_length_decode_and_longer_ones_are_reported(
    tmp_path: Path,
) -> None:
    path = tmp_path / "fd.pcap"
    command = encode_command("look_down")
    with path.open("wb") as handle:
        writer = dpkt.pcap.Writer(handle, linktype=227)  # Wireshark on can0, big-endian IDs
        writer.writepkt(canfd_frame(0x80000F01, command), ts=5.0)
        writer.writepkt(canfd_frame(0x80000F01, bytes(range(48))), ts=5.1)
        writer.writepkt(socketcan_frame(CanFrame(0, 0xF01, command, True), ">"), ts=5.2)
    frames, events, reader = read(path)
    assert events == []
    assert [(f.is_fd, len(f.data)) for f in frames] == [(True, 8), (True, 48), (False, 8)]
    assert frames[0].data == command
    decoded = ProtocolDecoder().feed(frames[0])
    assert decoded[0].topic == TOPIC_COMMAND and decoded[0].fields["name"] == "look_down"
    assert any("CAN FD" in w for w in decoded[0].warnings)
    assert all(
        isinstance(e, Event) for e in ProtocolDecoder().feed(frames[1])
    )  # 48 bytes: no crash
    assert reader.stats["long_fd_frames"] == 1
    assert any("more than 8" in n for n in reader.notes)


def test_can_fd_over_sll2_protocol_000d(tmp_path: Path) -> None:
    path = tmp_path / "fd-any.pcap"
    with path.open("wb") as handle:
        writer = dpkt.pcap.Writer(handle, linktype=276)
        header = struct.pack(">HHIHBB8s", 0x000D, 0, 7, 280, 0, 0, b"")
        writer.writepkt(header + canfd_frame(0x80000F01, b"\x01\x02\x03", "<"), ts=2.0)
    frames, events, _ = read(path)
    assert events == []
    assert [(f.can_id, f.data, f.is_fd, f.channel) for f in frames] == [
        (0xF01, b"\x01\x02\x03", True, "if7")
    ]


@settings(
    max_examples=80, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    link=st.sampled_from([113, 276]),
    protocol=st.sampled_from([0x000C, 0x000D, 0x000E]),
    frames=st.lists(st.binary(max_size=80), max_size=8),
)
def test_any_bytes_after_a_cooked_can_header_never_raise(
    tmp_path: Path, link: int, protocol: int, frames: list[bytes]
) -> None:
    path = tmp_path / "fuzz.pcap"
    with path.open("wb") as handle:
        writer = dpkt.pcap.Writer(handle, linktype=link)
        for body in frames:
            if link == 113:
                header = struct.pack(">HHH8sH", 0, 280, 0, b"", protocol)
            else:
                header = struct.pack(">HHIHBB8s", protocol, 0, 1, 280, 0, 0, b"")
            writer.writepkt(header + body, ts=1.0)
    got, _, _ = read(path)
    assert len(got) <= len(frames)
    assert all(len(f.data) <= 64 for f in got)


def test_a_capture_without_tcp_or_can_names_the_protocols_it_holds(tmp_path: Path) -> None:
    path = tmp_path / "xl.pcap"
    with path.open("wb") as handle:
        writer = dpkt.pcap.Writer(handle, linktype=276)
        header = struct.pack(">HHIHBB8s", 0x000E, 0, 5, 280, 0, 0, b"")  # CAN XL
        for i in range(3):
            writer.writepkt(header + bytes(24), ts=1.0 + i)
    frames, events, reader = read(path)
    assert frames == [] and events == []
    assert reader.notes == [
        "no TCP or CAN traffic in xl.pcap; link-layer protocols seen: 0x000E (3 packets) "
        "(0x000C is CAN, 0x000D CAN FD, 0x000E CAN XL)"
    ]
