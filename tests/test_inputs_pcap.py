"""pcap / pcapng input: link layers, TCP reassembly per flow and direction, faults, SocketCAN."""

from __future__ import annotations

import socket
from pathlib import Path
from typing import Any

import dpkt
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from analyzer.errors import UsageError
from analyzer.inputs import open_input
from analyzer.protocol.codec import encode_command
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.feedback import encode_attitude
from analyzer.protocol.framing import wrap_can, wrap_control
from analyzer.protocol.ids import GPS_ID
from analyzer.protocol.types import (
    FROM_IDU,
    INCOMPLETE,
    TO_IDU,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_UAV_GPS,
    CanFrame,
    Event,
    StreamChunk,
)
from analyzer.protocol.uav import encode_gps

CLIENT, SERVER = "10.0.0.5", "10.0.0.200"
CPORT, PORT = 50211, 2000
C0, S0 = 4_000_000_000, 77  # client ISN near the wrap-around
T0 = 1_700_000_000.0

CONTROL = wrap_control(encode_command("gimbal_control", pan_speed_dps=-5.0, tilt_speed_dps=0))
LOOK_DOWN = wrap_control(encode_command("look_down"))
GPS = wrap_can(GPS_ID, encode_gps(31.1234567, 118.1234567))
ATTITUDE = encode_attitude(pitch_deg=-10.0, yaw_deg=100.0, motor_yaw_deg=5.0)

SYN, ACK, FIN, PSH, RST = dpkt.tcp.TH_SYN, dpkt.tcp.TH_ACK, dpkt.tcp.TH_FIN, dpkt.tcp.TH_PUSH, 4


def ip_packet(src: str, dst: str, tcp: dpkt.tcp.TCP, v6: bool = False) -> Any:
    if v6:
        ip6 = dpkt.ip6.IP6(
            src=socket.inet_pton(socket.AF_INET6, src),
            dst=socket.inet_pton(socket.AF_INET6, dst),
            nxt=6,
            hlim=64,
            data=tcp,
        )
        ip6.plen = len(bytes(tcp))
        return ip6
    return dpkt.ip.IP(src=socket.inet_aton(src), dst=socket.inet_aton(dst), p=6, ttl=64, data=tcp)


def segment(
    to_idu: bool, seq: int, payload: bytes = b"", flags: int = ACK | PSH, **kw: Any
) -> tuple[str, str, dpkt.tcp.TCP]:
    sport, dport = (CPORT, PORT) if to_idu else (PORT, CPORT)
    tcp = dpkt.tcp.TCP(
        sport=kw.get("sport", sport),
        dport=kw.get("dport", dport),
        seq=seq % (1 << 32),
        flags=flags,
        data=payload,
    )
    src, dst = (CLIENT, SERVER) if to_idu else (SERVER, CLIENT)
    return src, dst, tcp


def session() -> list[tuple[str, str, dpkt.tcp.TCP]]:
    """A connection with glued, split, out-of-order and retransmitted frames both ways."""
    c, s = C0 + 1, S0 + 1
    glued = CONTROL + LOOK_DOWN
    return [
        segment(True, C0, flags=SYN),
        segment(False, S0, flags=SYN | ACK),
        segment(True, c, glued),  # two frames in one segment
        segment(True, c + 48 + 10, GPS[10:]),  # second half first
        segment(True, c + 48, GPS[:10]),
        segment(True, c + 48, GPS[:10]),  # retransmission
        segment(False, s, ATTITUDE[:20]),
        segment(False, s + 12, ATTITUDE[12:]),  # overlapping
        segment(True, c + 72, b"", flags=FIN | ACK),
    ]


def write_pcap(
    path: Path,
    packets: list[tuple[str, str, dpkt.tcp.TCP]],
    link: str = "ethernet",
    ng: bool = False,
    v6: bool = False,
) -> Path:
    linktype = {"ethernet": 1, "sll": 113, "sll2": 276, "raw": 101}[link]
    with path.open("wb") as f:
        writer: Any = (
            dpkt.pcapng.Writer(f, linktype=linktype)
            if ng
            else dpkt.pcap.Writer(f, linktype=linktype)
        )
        for i, (src, dst, tcp) in enumerate(packets):
            ip = ip_packet(src, dst, tcp, v6)
            ethtype = dpkt.ethernet.ETH_TYPE_IP6 if v6 else dpkt.ethernet.ETH_TYPE_IP
            frame: Any
            if link == "ethernet":
                frame = dpkt.ethernet.Ethernet(
                    src=b"\x02" * 6, dst=b"\x04" * 6, type=ethtype, data=ip
                )
            elif link == "sll":
                frame = dpkt.sll.SLL(ethtype=ethtype, data=ip)
            elif link == "sll2":
                frame = dpkt.sll2.SLL2(ethtype=ethtype, data=ip)
            else:
                frame = ip
            writer.writepkt(bytes(frame), ts=T0 + i * 0.01)
    return path


def decode(path: Path, **kw: Any) -> tuple[list[Any], list[Event], Any]:
    reader = open_input(str(path), **kw)
    items = list(reader)
    decoder = ProtocolDecoder()
    events: list[Event] = []
    for item in items:
        events.extend([item] if isinstance(item, Event) else decoder.feed(item))
    events.extend(decoder.close())
    return items, events, reader


def check_session(events: list[Event]) -> None:
    topics = [(e.topic, e.fields.get("direction")) for e in events]
    assert topics == [
        (TOPIC_COMMAND, TO_IDU),
        (TOPIC_COMMAND, TO_IDU),
        (TOPIC_UAV_GPS, TO_IDU),
        (TOPIC_GIMBAL_ATTITUDE, FROM_IDU),
    ]
    assert events[0].fields["name"] == "gimbal_control"
    assert events[0].fields["pan_speed_dps"] == -5.0
    assert events[1].fields["name"] == "look_down"
    assert events[2].fields["latitude_deg"] == pytest.approx(31.1234567)
    assert events[3].fields["yaw_deg"] == 100.0


@pytest.mark.parametrize("link", ["ethernet", "sll", "sll2", "raw"])
@pytest.mark.parametrize("ng", [False, True])
def test_session_decodes_in_both_directions(tmp_path: Path, link: str, ng: bool) -> None:
    path = write_pcap(tmp_path / ("s.pcapng" if ng else "s.pcap"), session(), link, ng)
    items, events, reader = decode(path)
    check_session(events)
    chunks = [i for i in items if isinstance(i, StreamChunk)]
    assert {c.source for c in chunks} == {f"tcp:{CLIENT}:{CPORT}-{SERVER}:{PORT}"}
    to_idu = b"".join(c.data for c in chunks if c.direction == TO_IDU)
    assert to_idu == CONTROL + LOOK_DOWN + GPS
    assert b"".join(c.data for c in chunks if c.direction == FROM_IDU) == ATTITUDE
    stats = reader.stats
    assert stats["bytes_duplicate"] == 10 + 8 and stats["bytes_missing"] == 0
    assert stats["bytes_in"] == stats["bytes_delivered"] + stats["bytes_duplicate"]
    assert reader.position_bytes == reader.size_bytes


def test_ipv6_session(tmp_path: Path) -> None:
    packets = [
        ("fd00::5" if s == CLIENT else "fd00::200", "fd00::200" if s == CLIENT else "fd00::5", t)
        for s, _d, t in session()
    ]
    _, events, _ = decode(write_pcap(tmp_path / "v6.pcap", packets, v6=True))
    check_session(events)
    assert events[0].source == f"tcp:[fd00::5]:{CPORT}-[fd00::200]:{PORT}"


def test_other_port_is_ignored_unless_asked_for(tmp_path: Path) -> None:
    packets = [
        segment(True, 10, CONTROL, sport=40000, dport=2001),
        segment(True, 5000, CONTROL, sport=40001, dport=80),
    ]
    path = write_pcap(tmp_path / "p.pcap", packets)
    _, events, reader = decode(path)
    assert events == [] and reader.stats["other_packets"] == 2
    _, events, _ = decode(path, port=2001)
    assert [e.fields["name"] for e in events] == ["gimbal_control"]
    assert events[0].fields["direction"] == TO_IDU


def test_lost_segment_is_a_diagnostic_and_decoding_resumes(tmp_path: Path) -> None:
    c = C0 + 1
    packets = [
        segment(True, C0, flags=SYN),
        segment(True, c, CONTROL),
        segment(True, c + 24 + 5, LOOK_DOWN[5:]),  # the first 5 bytes were never captured
        segment(True, c + 48, CONTROL),
    ]
    _, events, _ = decode(write_pcap(tmp_path / "lost.pcap", packets))
    gaps = [e for e in events if e.fields.get("kind") == INCOMPLETE and "missing_bytes" in e.fields]
    assert len(gaps) == 1 and gaps[0].fields["missing_bytes"] == 5
    assert gaps[0].fields["direction"] == TO_IDU
    commands = [e for e in events if e.topic == TOPIC_COMMAND]
    assert [e.fields["name"] for e in commands] == ["gimbal_control", "gimbal_control"]


def test_two_connections_on_the_same_ports_are_kept_apart(tmp_path: Path) -> None:
    packets = [
        segment(True, 100, flags=SYN),
        segment(True, 101, CONTROL[:10]),  # cut off: the connection is reset
        segment(True, 111, b"", flags=RST),
        segment(True, 9000, flags=SYN),
        segment(True, 9001, LOOK_DOWN),
    ]
    items, events, _ = decode(write_pcap(tmp_path / "two.pcap", packets))
    sources = [i.source for i in items if isinstance(i, StreamChunk)]
    assert sources[0] != sources[-1] and sources[-1].endswith("#2")
    assert [e.fields.get("name") for e in events if e.topic == TOPIC_COMMAND] == ["look_down"]
    assert any(e.topic == TOPIC_DIAGNOSTICS for e in events)  # the cut-off frame


@pytest.mark.parametrize(
    ("cut", "words"),
    [
        (lambda b: b[:-60], "too short"),  # not even the IP header of the last packet
        (lambda b: b + b"\x01\x02", "cut off inside the header"),  # half a record header
        (lambda b: b[:-10], "captured shorter than sent"),  # inside the last segment's data
    ],
)
def test_cut_off_capture_file_ends_with_a_diagnostic(tmp_path: Path, cut: Any, words: str) -> None:
    packets = [*session()[:-1], segment(True, C0 + 73, CONTROL)]
    path = write_pcap(tmp_path / "cut.pcap", packets)
    path.write_bytes(cut(path.read_bytes()))
    _, events, _ = decode(path)
    problems = [e for e in events if e.topic == TOPIC_DIAGNOSTICS]
    assert any(words in e.fields["detail"] for e in problems), problems
    names = [e.fields.get("name") for e in events if e.topic == TOPIC_COMMAND]
    assert names[:2] == ["gimbal_control", "look_down"]


def test_socketcan_capture_gives_can_frames(tmp_path: Path) -> None:
    path = tmp_path / "can.pcap"
    with path.open("wb") as f:
        writer = dpkt.pcap.Writer(f, linktype=227)
        data = encode_command("look_down")
        header = (0x80000000 | 0x00000F01).to_bytes(4, "big") + bytes([8, 0, 0, 0])
        writer.writepkt(header + data, ts=T0)
        writer.writepkt((0x123).to_bytes(4, "big") + bytes([2, 0, 0, 0]) + b"\x01\x02", ts=T0)
    items = list(open_input(str(path)))
    assert items == [
        CanFrame(T0, 0xF01, data, True, "pcap"),
        CanFrame(T0, 0x123, b"\x01\x02", False, "pcap"),
    ]


def test_not_a_capture_is_a_usage_error(tmp_path: Path) -> None:
    path = tmp_path / "fake.pcap"
    path.write_bytes(b"hello, this is text")
    with pytest.raises(UsageError, match="cannot read"):
        open_input(str(path))


def test_unsupported_link_type_is_a_usage_error(tmp_path: Path) -> None:
    path = tmp_path / "wifi.pcap"
    with path.open("wb") as f:
        dpkt.pcap.Writer(f, linktype=105)
    with pytest.raises(UsageError, match="link type 105"):
        open_input(str(path))


@settings(
    max_examples=100, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    st.sampled_from([1, 113, 276, 101, 0, 227]),
    st.lists(st.binary(max_size=120), max_size=12),
)
def test_arbitrary_packets_never_raise(tmp_path: Path, link: int, packets: list[bytes]) -> None:
    path = tmp_path / "fuzz.pcap"
    with path.open("wb") as f:
        writer = dpkt.pcap.Writer(f, linktype=link)
        for i, packet in enumerate(packets):
            writer.writepkt(packet, ts=T0 + i)
    reader = open_input(str(path))
    for item in reader:
        assert isinstance(item, (CanFrame, StreamChunk, Event))
    assert reader.stats["packets"] == len(packets)
