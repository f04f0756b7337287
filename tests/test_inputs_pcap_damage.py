"""pcap / pcapng as real machines leave them: TCP offload, FCS link types, wrong record lengths,
damaged blocks, little-endian SocketCAN; and the bounds of TCP reassembly."""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from analyzer.inputs import open_input
from analyzer.inputs.pcap.tcp_flows import FlowTable
from analyzer.inputs.pcap.tcp_reassembly import MAX_PENDING_SEGMENTS, TcpDirection
from analyzer.protocol.codec import encode_command
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.feedback import encode_attitude
from analyzer.protocol.framing import wrap_control
from analyzer.protocol.types import BAD_FRAME, TOPIC_COMMAND, CanFrame, Event

GCS, IDU = bytes([192, 168, 42, 10]), bytes([192, 168, 42, 200])
GPORT, PORT = 50312, 2000
T0 = 1_715_680_800.0
COMMANDS = [
    wrap_control(encode_command("gimbal_control", pan_speed_dps=float(i), tilt_speed_dps=0))
    for i in range(20)
]
ATTITUDE = encode_attitude(pitch_deg=-10.0, yaw_deg=100.0, motor_yaw_deg=5.0)


def tcp(sport: int, dport: int, seq: int, payload: bytes, flags: int = 0x18) -> bytes:
    return struct.pack(">HHIIBBHHH", sport, dport, seq, 1, 5 << 4, flags, 65535, 0, 0) + payload


def ipv4(src: bytes, dst: bytes, segment: bytes, total: int | None = None) -> bytes:
    length = 20 + len(segment) if total is None else total
    header = struct.pack(">BBHHHBBH4s4s", 0x45, 0, length, 1, 0x4000, 64, 6, 0, src, dst)
    return header + segment


def ethernet(ip: bytes) -> bytes:
    return b"\x04" * 6 + b"\x02" * 6 + b"\x08\x00" + ip


def gcs_capture(offload: bool) -> list[bytes]:
    """Ethernet frames of a ground station sending 20 commands to the IDU and getting
    feedback, captured on the ground-station laptop. With TCP segmentation offload the
    kernel hands the capture its outgoing packets before the NIC fills in the IPv4 total
    length: Wireshark shows 'reported as 0, presumed to be because of TCP segmentation
    offload'; with large sends it is larger than the captured packet."""
    frames = [ethernet(ipv4(GCS, IDU, tcp(GPORT, PORT, 999, b"", flags=0x02)))]
    seq = 1000
    for i, command in enumerate(COMMANDS):
        total = None
        if offload:
            total = 0 if i % 2 else 20 + 20 + len(command) + 1400  # never filled in / GSO
        frames.append(ethernet(ipv4(GCS, IDU, tcp(GPORT, PORT, seq, command), total)))
        seq += len(command)
    frames.append(ethernet(ipv4(IDU, GCS, tcp(PORT, GPORT, 5000, ATTITUDE))))
    return frames


def pcap_bytes(frames: list[bytes], link: int = 1, records: list[bytes] | None = None) -> bytes:
    out = struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 262144, link)
    for i, frame in enumerate(frames):
        ts = T0 + i * 0.05
        out += struct.pack("<IIII", int(ts), round((ts % 1) * 1e6), len(frame), len(frame))
        out += frame
    return out


def pcapng_bytes(frames: list[bytes], link_field: int = 1, options: bytes = b"") -> bytes:
    def block(kind: int, body: bytes) -> bytes:
        body += b"\0" * (-len(body) % 4)
        size = len(body) + 12
        return struct.pack("<II", kind, size) + body + struct.pack("<I", size)

    out = block(0x0A0D0D0A, struct.pack("<IHHq", 0x1A2B3C4D, 1, 0, -1))
    out += block(1, struct.pack("<II", link_field, 262144) + options)
    for i, frame in enumerate(frames):
        stamp = round((T0 + i * 0.05) * 1e6)
        body = struct.pack("<IIIII", 0, stamp >> 32, stamp & 0xFFFFFFFF, len(frame), len(frame))
        out += block(6, body + frame)
    return out


def decode(path: Path) -> tuple[list[Event], list[Event], Any]:
    """(commands, diagnostics, reader)."""
    reader = open_input(str(path))
    decoder = ProtocolDecoder()
    events: list[Event] = []
    with reader:
        for item in reader:
            events.extend([item] if isinstance(item, Event) else decoder.feed(item))
    events.extend(decoder.close())
    commands = [e for e in events if e.topic == TOPIC_COMMAND]
    problems = [e for e in events if e.topic == "/diagnostics"]
    return commands, problems, reader


def pan_speeds(commands: list[Event]) -> list[float]:
    return [e.fields["pan_speed_dps"] for e in commands]


# -- TCP segmentation offload ----------------------------------------------------------------


def test_capture_on_the_ground_station_with_tcp_offload_decodes_every_command(
    tmp_path: Path,
) -> None:
    path = tmp_path / "gcs.pcap"
    path.write_bytes(pcap_bytes(gcs_capture(offload=True)))
    commands, problems, reader = decode(path)
    assert pan_speeds(commands) == [float(i) for i in range(20)]
    assert problems == []
    assert reader.stats["bad_packets"] == 0
    assert reader.stats["offloaded_packets"] == 20
    assert len(reader.notes) == 1 and "segmentation offload" in reader.notes[0]


def test_snapped_packet_is_still_reported_as_cut_not_offloaded(tmp_path: Path) -> None:
    frames = gcs_capture(offload=False)
    data = bytearray(pcap_bytes(frames))
    # Record 2 (the first command) captured with a snap length of 60 bytes.
    offset = 24 + 16 + len(frames[0])
    struct.pack_into("<I", data, offset + 8, 60)
    del data[offset + 16 + 60 : offset + 16 + len(frames[1])]
    path = tmp_path / "snapped.pcap"
    path.write_bytes(bytes(data))
    commands, problems, reader = decode(path)
    assert reader.stats["truncated_packets"] == 1 and reader.stats["offloaded_packets"] == 0
    assert len(commands) == 19
    assert any("captured shorter than sent" in p.fields["detail"] for p in problems)


# -- FCS bits in the link type ---------------------------------------------------------------


def test_link_type_with_fcs_length_bits_reads_as_ethernet(tmp_path: Path) -> None:
    path = tmp_path / "fcs.pcap"
    path.write_bytes(pcap_bytes(gcs_capture(offload=False), link=0x30000001))
    commands, problems, _ = decode(path)
    assert len(commands) == 20 and problems == []


def test_fcs_present_bytes_are_cut_off_even_with_offload(tmp_path: Path) -> None:
    # LT_FCS_DATALINK_EXT(2): a 4-byte FCS at the end of every frame.
    frames = [f + b"\xde\xad\xbe\xef" for f in gcs_capture(offload=True)]
    path = tmp_path / "fcs4.pcap"
    path.write_bytes(pcap_bytes(frames, link=0x24000001))
    commands, problems, _ = decode(path)
    assert pan_speeds(commands) == [float(i) for i in range(20)]
    assert problems == []


def test_pcapng_interface_with_fcs_bits_and_fcslen_option(tmp_path: Path) -> None:
    frames = [f + b"\xde\xad\xbe\xef" for f in gcs_capture(offload=True)]
    fcslen = struct.pack("<HHB3x", 13, 1, 32) + struct.pack("<HH", 0, 0)  # if_fcslen: 32 bits
    path = tmp_path / "fcs.pcapng"
    path.write_bytes(pcapng_bytes(frames, link_field=0x30000001, options=fcslen))
    commands, problems, _ = decode(path)
    assert pan_speeds(commands) == [float(i) for i in range(20)]
    assert problems == []


# -- damaged records -------------------------------------------------------------------------


def record_offsets(data: bytes) -> list[int]:
    offsets, pos = [], 24
    while pos < len(data):
        offsets.append(pos)
        pos += 16 + struct.unpack_from("<I", data, pos + 8)[0]
    return offsets


def test_a_wrong_captured_length_does_not_swallow_the_rest(tmp_path: Path) -> None:
    data = bytearray(pcap_bytes(gcs_capture(offload=False)))
    at = record_offsets(bytes(data))[6]
    caplen = struct.unpack_from("<I", data, at + 8)[0]
    struct.pack_into("<II", data, at + 8, caplen + 300, caplen + 300)  # plausible, but wrong
    path = tmp_path / "caplen.pcap"
    path.write_bytes(bytes(data))
    commands, problems, reader = decode(path)
    assert pan_speeds(commands) == [float(i) for i in range(20)]
    assert len(problems) == 1 and problems[0].fields["kind"] == BAD_FRAME
    assert "wrong captured length" in problems[0].fields["detail"]
    assert reader.stats["packets"] == 22


def test_a_too_short_captured_length_loses_one_record_and_resynchronises(tmp_path: Path) -> None:
    data = bytearray(pcap_bytes(gcs_capture(offload=False)))
    at = record_offsets(bytes(data))[6]
    struct.pack_into("<I", data, at + 8, 20)
    path = tmp_path / "short.pcap"
    path.write_bytes(bytes(data))
    commands, problems, _ = decode(path)
    assert pan_speeds(commands) == [float(i) for i in range(20) if i != 5]
    details = " | ".join(p.fields["detail"] for p in problems)
    assert "skipped to the next record" in details


def test_pcapng_block_with_a_huge_length_is_described_in_words(tmp_path: Path) -> None:
    data = bytearray(pcapng_bytes(gcs_capture(offload=False)))
    # The sixth enhanced packet block claims 4 GiB.
    pos, blocks = 0, []
    while pos < len(data):
        blocks.append(pos)
        pos += struct.unpack_from("<I", data, pos + 4)[0]
    struct.pack_into("<I", data, blocks[2 + 5] + 4, 0xFFFFFFF0)
    path = tmp_path / "huge.pcapng"
    path.write_bytes(bytes(data))
    commands, problems, _ = decode(path)
    damage = [p for p in problems if p.fields["kind"] == BAD_FRAME]
    assert len(damage) == 1
    detail = damage[0].fields["detail"]
    assert "claims 4,294,967,280 bytes" in detail and "NeedData" not in detail
    assert "skipped to the next block" in detail
    assert pan_speeds(commands) == [float(i) for i in range(20) if i != 4]


@settings(max_examples=40, deadline=None)
@given(record=st.integers(1, 21), caplen=st.integers(0, 5000))
def test_any_wrong_caplen_costs_at_most_its_record(
    tmp_path_factory: Any, record: int, caplen: int
) -> None:
    data = bytearray(pcap_bytes(gcs_capture(offload=False)))
    at = record_offsets(bytes(data))[record]
    struct.pack_into("<II", data, at + 8, caplen, max(caplen, 100))
    path = tmp_path_factory.mktemp("c") / "x.pcap"
    path.write_bytes(bytes(data))
    commands, problems, _ = decode(path)
    expected = [float(i) for i in range(20)]
    got = pan_speeds(commands)
    assert set(got) <= set(expected)
    if len(got) < 20:  # every loss is reported
        assert problems
    # A record cut short also costs the command after it (the stream framer meets the
    # hole mid-frame). Losing more means the wrong length landed on a record header.
    if len(got) < 18:
        details = " ".join(p.fields["detail"] for p in problems)
        assert "hidden inside them" in details


@settings(max_examples=40, deadline=None)
@given(st.data())
def test_mangled_pcapng_never_raises_and_reports_its_losses(
    tmp_path_factory: Any, data: st.DataObject
) -> None:
    original = pcapng_bytes(gcs_capture(offload=False))
    raw = bytearray(original)
    for _ in range(data.draw(st.integers(1, 3))):
        raw[data.draw(st.integers(0, len(raw) - 1))] = data.draw(st.integers(0, 255))
    cut = data.draw(st.integers(len(raw) // 2, len(raw)))
    folder = tmp_path_factory.mktemp("n")
    path = folder / "x.pcapng"
    path.write_bytes(bytes(raw[:cut]))
    try:
        commands, problems, _ = decode(path)
    except Exception as exc:  # only an unreadable file header may refuse the file
        assert type(exc).__name__ == "UsageError"
        return
    # A cut that falls on a block boundary leaves a shorter but whole file: what counts
    # as lost is what the same cut of the undamaged capture still holds.
    intact = folder / "intact.pcapng"
    intact.write_bytes(original[:cut])
    whole, _, _ = decode(intact)
    if len(commands) < len(whole):
        assert problems


# -- SocketCAN -------------------------------------------------------------------------------


def test_little_endian_socketcan_ids_are_read_and_noted(tmp_path: Path) -> None:
    data = encode_command("look_down")
    frames = [
        (0x80000000 | 0xF01).to_bytes(4, "little") + bytes([8, 0, 0, 0]) + data,
        (0x123).to_bytes(4, "little") + bytes([2, 0, 0, 0]) + b"\x01\x02",
    ]
    path = tmp_path / "le.pcap"
    path.write_bytes(pcap_bytes(frames, link=227))
    reader = open_input(str(path))
    items = list(reader)
    assert [(f.can_id, f.extended) for f in items if isinstance(f, CanFrame)] == [
        (0xF01, True),
        (0x123, False),
    ]
    assert any("little-endian" in note for note in reader.notes)


# -- bounds of TCP reassembly ----------------------------------------------------------------


def test_a_syn_flood_keeps_the_connection_table_bounded() -> None:
    table = FlowTable(max_flows=100)
    for port in range(10_000):
        table.segment((("10.0.0.9", port), ("10.0.0.200", 2000)), "f", "gs_to_idu", 7, b"", 0.0, 2)
        assert len(table) <= 100
    assert table.given_up.flows == 9_900
    assert table.totals()["flows"] == 10_000


def test_out_of_order_data_over_many_connections_is_bounded_and_accounted() -> None:
    table = FlowTable(max_pending_total=1 << 20)
    delivered = 0
    for port in range(200):
        key = (("10.0.0.9", 40000 + port), ("10.0.0.200", 2000))
        table.segment(key, f"f{port}", "gs_to_idu", 0, b"", 0.0, 2)  # SYN
        for hole in range(4):  # 4 holes of 1 byte, 16 KiB behind each
            out = table.segment(key, "", "gs_to_idu", 2 + hole * 16385, b"x" * 16384, 0.0, 0x18)
            delivered += sum(len(r.data) for _f, _d, rs in out for r in rs if hasattr(r, "data"))
        assert table.pending <= 1 << 20
    totals = table.totals()
    assert table.given_up.bytes > 0
    held = table.pending
    assert totals["bytes_in"] == (
        totals["bytes_delivered"] + totals["bytes_duplicate"] + totals["bytes_out_of_window"] + held
    )
    assert delivered == totals["bytes_delivered"]


def test_many_tiny_out_of_order_segments_are_bounded_by_count() -> None:
    state = TcpDirection()
    state.syn(0)
    for i in range(3 * MAX_PENDING_SEGMENTS):
        state.segment(2 + 2 * i, b"x", 0.0)  # every other byte missing
        assert len(state._pending) <= MAX_PENDING_SEGMENTS + 1
    assert state.gaps > 0
