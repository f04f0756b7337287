"""The Wireshark export, run by tshark, shows the frames, values and CRC errors we decode."""

from __future__ import annotations

import io
import json
import os
import random
import shutil
import subprocess
import sys
from collections import defaultdict
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import dpkt
import pytest

from analyzer.export.wireshark import command_abbr, feedback_abbr, lua_text, status_abbr
from analyzer.protocol.codec import encode_command
from analyzer.protocol.command_table import BY_CODE
from analyzer.protocol.crc import crc_bytes
from analyzer.protocol.feedback import LAYOUTS, encode_attitude, encode_ranging
from analyzer.protocol.fields import Field
from analyzer.protocol.framing import wrap_can, wrap_control
from analyzer.protocol.ids import (
    ALTITUDE_ID,
    CONTROL_ID,
    GPS_ID,
    TEXT_END_ID,
    TEXT_ID,
    UAV_ATTITUDE_ID,
)
from analyzer.protocol.uav import STATUS_FRAMES, encode_altitude, encode_gps, encode_uav_attitude

ROOT = Path(__file__).resolve().parent.parent
TSHARK = shutil.which("tshark")
# CI installs tshark and sets this, so that a missing tshark fails there instead of skipping.
REQUIRED = os.environ.get("GIMBAL_REQUIRE_TSHARK") == "1"
pytestmark = pytest.mark.skipif(
    TSHARK is None and not REQUIRED, reason="tshark is not installed (Debian package tshark)"
)
CLI = [sys.executable, "-c", "import sys; from analyzer.cli import main; sys.exit(main())"]

Item = tuple[Any, ...]


@pytest.fixture(scope="module")
def lua(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("lua") / "gimbal.lua"
    path.write_text(lua_text(), encoding="utf-8")
    return path


def _flatten(tree: Any, out: dict[str, list[Any]]) -> None:
    if isinstance(tree, list):
        for item in tree:
            _flatten(item, out)
    elif isinstance(tree, dict):
        for key, value in tree.items():
            if (isinstance(value, (dict, list)) and key.endswith("_tree")) or key == "_ws.expert":
                _flatten(value, out)
            elif isinstance(value, list):
                for v in value:
                    if isinstance(v, (dict, list)):
                        _flatten(v, out)
                    else:
                        out.setdefault(key, []).append(v)
            else:
                out.setdefault(key, []).append(value)


def tshark_json(lua: Path, pcap: Path) -> list[dict[str, Any]]:
    assert TSHARK is not None, "tshark is not installed (Debian package tshark)"
    cmd = [TSHARK, "-n", "-X", f"lua_script:{lua}", "-r", str(pcap), "-T", "json"]
    run = subprocess.run(
        [*cmd, "--no-duplicate-keys"], capture_output=True, text=True, timeout=120, encoding="utf-8"
    )
    assert run.returncode == 0, run.stderr
    assert "Lua" not in run.stderr, run.stderr
    assert "Lua Error" not in run.stdout, "the dissector failed on some frame"
    packets: list[dict[str, Any]] = json.loads(run.stdout)
    return packets


def _pdus(packet: dict[str, Any]) -> Iterator[dict[str, list[Any]]]:
    trees = packet["_source"]["layers"].get("gimbal", [])
    for tree in trees if isinstance(trees, list) else [trees]:
        flat: dict[str, list[Any]] = {}
        _flatten(tree, flat)
        yield flat


def _value(f: Field, text: str) -> Any:
    if f.labels is not None or f.boolean:
        return int(text)
    return round(float(text), 9)


def _wireshark_item(pdu: dict[str, list[Any]]) -> Item | None:
    """One frame as tshark shows it, in the same form as ``_our_item``."""
    item = _wireshark_frame(pdu)
    if item is None or item[0] in ("incomplete", "crc_mismatch"):
        return item
    doubts = len(pdu.get("gimbal.warning", [])) + len(pdu.get("gimbal.unknown", []))
    return (*item, doubts)


def _wireshark_frame(pdu: dict[str, list[Any]]) -> Item | None:
    if "gimbal.incomplete" in pdu:
        return ("incomplete",)
    if "gimbal.type" not in pdu:
        return None  # padding or skipped bytes
    if pdu["gimbal.crc.status"] == ["0"]:
        assert "gimbal.crc.bad" in pdu  # flagged as expert info
        return ("crc_mismatch",)
    frame_type = int(pdu["gimbal.type"][0], 16)
    if "gimbal.command" in pdu:
        s_id, cmd = int(pdu["gimbal.s_id"][0], 16), int(pdu["gimbal.cmd"][0], 16)
        row = BY_CODE.get((s_id, cmd))
        values = {
            command_abbr(row, f): _value(f, pdu[command_abbr(row, f)][0])
            for f in (row.all_fields() if row else ())
            if command_abbr(row, f) in pdu
        }
        return ("command", s_id, cmd, pdu["gimbal.command"][0], tuple(sorted(values.items())))
    if frame_type in LAYOUTS:
        layout = LAYOUTS[frame_type]
        fields = layout.layout.fields
        values = {
            feedback_abbr(layout, f): _value(f, pdu[feedback_abbr(layout, f)][0]) for f in fields
        }
        return (layout.topic, tuple(sorted(values.items())))
    status = STATUS_FRAMES.get(int(pdu["gimbal.can_id"][0], 16))
    if status is None:
        return None  # text frames (joined by the decoder) and other CAN IDs
    fields = status.layout.fields
    values = {status_abbr(status, f): _value(f, pdu[status_abbr(status, f)][0]) for f in fields}
    return (status.topic, tuple(sorted(values.items())))


def _our_value(f: Field, event: dict[str, Any]) -> Any:
    if f.labels is not None:
        return int(event[f.code_name])
    if f.boolean:
        return int(bool(event[f.name]))
    return round(float(event[f.name]), 9)


def _our_item(event: dict[str, Any]) -> Item | None:
    """One event: what it is, its values, and how many doubts (warnings) it carries."""
    item = _our_frame(event)
    if item is None or event["topic"] == "/diagnostics":
        return item
    return (*item, len(event["warnings"]))


def _our_frame(event: dict[str, Any]) -> Item | None:
    topic = event["topic"]
    if topic == "/diagnostics":
        if event["kind"] == "crc_mismatch":
            return ("crc_mismatch",)
        if event["kind"] == "incomplete" and "cut short" in event["detail"]:
            return ("incomplete",)
        return None  # garbage is reported in runs, the end of the capture only here
    if topic == "/gimbal/command":
        row = BY_CODE.get((event["s_id"], event["cmd"]))
        fields = [f for f in row.all_fields() if f.name in event] if row else []
        values = {command_abbr(row, f): _our_value(f, event) for f in fields if row}
        return (
            "command",
            event["s_id"],
            event["cmd"],
            event["name"],
            tuple(sorted(values.items())),
        )
    for layout in LAYOUTS.values():
        if layout.topic == topic:
            fields = layout.layout.fields
            values = {feedback_abbr(layout, f): _our_value(f, event) for f in fields}
            return (topic, tuple(sorted(values.items())))
    status = next((s for s in STATUS_FRAMES.values() if s.topic == topic), None)
    if status is None:
        return None  # /uav/text: Wireshark shows its frames one by one
    values = {status_abbr(status, f): _our_value(f, event) for f in status.layout.fields}
    return (topic, tuple(sorted(values.items())))


def by_packet_time(items: list[tuple[float, str, Item]]) -> dict[int, list[Item]]:
    out: dict[int, list[Item]] = defaultdict(list)
    for time, _, item in items:
        out[round(time * 1e6)].append(item)
    return {t: sorted(v, key=repr) for t, v in sorted(out.items())}


def compare(
    lua: Path, pcap: Path, *, exact: bool = True
) -> tuple[dict[int, list[Item]], list[dict[str, Any]]]:
    """What tshark shows must be what ``decode --json`` gives: the same frames, values,
    CRC errors and cut-short frames in the same order, and (``exact``) in the same packets.

    Without ``exact``, Wireshark may show a frame later than the decoder, never earlier:
    after a frame cut short, the frame that follows can start inside bytes TCP has
    already joined, where TCP cannot begin a new PDU; the dissector then waits and
    shows them with the next segment.
    """
    packets = tshark_json(lua, pcap)
    theirs: list[tuple[float, str, Item]] = []
    for packet in packets:
        time = float(packet["_source"]["layers"]["frame"]["frame.time_epoch"])
        for pdu in _pdus(packet):
            item = _wireshark_item(pdu)
            if item is not None:
                theirs.append((time, pdu["gimbal.direction"][0], item))
    run = subprocess.run(
        [*CLI, "decode", "--json", str(pcap)],
        capture_output=True,
        text=True,
        timeout=120,
        encoding="utf-8",
    )
    assert run.returncode == 0, run.stderr
    ours: list[tuple[float, str, Item]] = []
    for line in run.stdout.splitlines():
        event = json.loads(line)
        item = _our_item(event)
        if item is not None:
            ours.append((event["time"], event["direction"], item))
    for direction in {d for _, d, _ in ours} | {d for _, d, _ in theirs}:
        mine = [(t, i) for t, d, i in ours if d == direction]
        shown = [(t, i) for t, d, i in theirs if d == direction]
        assert [i for _, i in shown] == [i for _, i in mine], direction
        assert all(a >= b - 1e-9 for (a, _), (b, _) in zip(shown, mine, strict=True)), direction
    expected = by_packet_time(ours)
    if exact:
        assert by_packet_time(theirs) == expected
    return expected, packets


def test_sample_capture_shows_what_decode_gives(lua: Path) -> None:
    expected, _ = compare(lua, ROOT / "samples" / "idu-tcp.pcap")
    items = [item for group in expected.values() for item in group]
    assert len(items) > 100
    names = {item[3] for item in items if item[0] == "command"}
    assert len(names) >= 15  # every kind of command in the sample made it through
    assert {item[0] for item in items} >= {"/gimbal/attitude", "/gimbal/ranging", "/uav/gps"}


def _labels_and_units(lua: Path, pcap: Path) -> str:
    assert TSHARK is not None
    cmd = [TSHARK, "-n", "-X", f"lua_script:{lua}", "-r", str(pcap), "-V", "-O", "gimbal"]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=120, encoding="utf-8").stdout


def test_values_are_shown_with_units_and_labels(lua: Path) -> None:
    text = _labels_and_units(lua, ROOT / "samples" / "idu-tcp.pcap")
    assert "pan_speed_dps: -5.00 deg/s (raw -500)" in text
    assert "control_mode: locking (3)" in text
    assert "action: zoom_in (1)" in text
    assert "palette: " in text
    assert "CRC status: Good (1)" in text
    assert "CRC status: Not set (00 00) (2)" in text
    assert "Command: specified_angle (Specified Angle)" in text


# -- a capture made here: frames split across and glued within segments, damaged frames ------

T0 = 1_700_000_000.0
CLIENT, IDU = "10.1.1.5", "10.1.1.200"
CPORT, PORT = 40123, 2000


def _to_idu_stream(cut_short: bool = False) -> bytes:
    frames = [
        wrap_control(encode_command("gimbal_control", pan_speed_dps=-5, tilt_speed_dps=12.5)),
        wrap_control(
            encode_command("specified_angle", pitch_deg=-45, coordinate_system="airframe")
        ),
        wrap_can(GPS_ID, encode_gps(31.1234567, 118.1234567)),
        b"\x13\x37noise",
        wrap_can(ALTITUDE_ID, encode_altitude(506.78), with_crc=True),
        wrap_can(UAV_ATTITUDE_ID, encode_uav_attitude(1.5, -2.25, -120.5)),
        wrap_control(encode_command("palette", palette="iron_red")),
        wrap_control(encode_command("zoom", action="zoom_in")),
        wrap_can(CONTROL_ID, encode_command("snapshot", mode="continuous", shots=4)),
        wrap_control(encode_command("tap_focus", x=100, y=8000)),
    ]
    bad = bytearray(wrap_control(encode_command("recording", action="start")))
    bad[-1] ^= 0xFF  # wrong CRC
    frames.insert(4, bytes(bad))
    if cut_short:  # a frame cut short, then a whole one
        frames.insert(7, wrap_control(encode_command("look_down"))[:10])
    frames.append(
        wrap_control(encode_command("gimbal_control", pan_speed_dps=100.01, check_range=False))
    )
    return b"".join(frames)


def _from_idu_stream() -> bytes:
    attitude = encode_attitude(pitch_deg=-29.69, yaw_deg=135, motor_yaw_deg=-1.25, control_mode=1)
    ranging = encode_ranging(
        distance_m=181.5, height_m=-4.4, latitude_deg=31.1, longitude_deg=-118.2
    )
    damaged = bytearray(ranging)
    damaged[20] ^= 0x01
    unpadded = attitude[:27]  # the zero padding after the CRC is optional
    return attitude + ranging + bytes(damaged) + unpadded + ranging


def _segments(stream: bytes, sizes: list[int]) -> list[bytes]:
    out, i, k = [], 0, 0
    while i < len(stream):
        out.append(stream[i : i + sizes[k % len(sizes)]])
        i += sizes[k % len(sizes)]
        k += 1
    return out


def _split_capture(
    path: Path,
    sizes: list[int],
    port: int = PORT,
    streams: tuple[bytes, bytes] | None = None,
    cut_short: bool = False,
) -> Path:
    """Both directions cut into segments of the given sizes, interleaved in time."""
    down_stream, up_stream = streams or (_to_idu_stream(cut_short), _from_idu_stream())
    buffer = io.BytesIO()
    writer = dpkt.pcap.Writer(buffer, linktype=dpkt.pcap.DLT_EN10MB)
    seq = {True: 1000, False: 5000}
    tick = 0
    down = _segments(down_stream, sizes)
    up = _segments(up_stream, list(reversed(sizes)))
    for i in range(max(len(down), len(up))):
        for to_idu, parts in ((True, down), (False, up)):
            if i >= len(parts):
                continue
            sport, dport = (CPORT, port) if to_idu else (port, CPORT)
            src, dst = (CLIENT, IDU) if to_idu else (IDU, CLIENT)
            tcp = dpkt.tcp.TCP(
                sport=sport,
                dport=dport,
                seq=seq[to_idu],
                ack=seq[not to_idu],
                flags=dpkt.tcp.TH_ACK | dpkt.tcp.TH_PUSH,
                data=parts[i],
            )
            seq[to_idu] += len(parts[i])
            ip = dpkt.ip.IP(
                src=bytes(map(int, src.split("."))),
                dst=bytes(map(int, dst.split("."))),
                p=6,
                ttl=64,
                data=tcp,
            )
            frame = dpkt.ethernet.Ethernet(src=b"\x02" * 6, dst=b"\x04" * 6, data=ip)
            writer.writepkt(bytes(frame), ts=T0 + tick * 0.01)
            tick += 1
    path.write_bytes(buffer.getvalue())
    return path


@pytest.mark.parametrize(
    "sizes",
    [[1], [7, 3, 24, 50, 2], [24, 24, 5, 19, 32, 1, 31], [200]],
    ids=["byte-by-byte", "odd", "mixed", "glued"],
)
def test_split_and_glued_frames_are_reassembled(
    lua: Path, tmp_path: Path, sizes: list[int]
) -> None:
    pcap = _split_capture(tmp_path / "split.pcap", sizes)
    expected, packets = compare(lua, pcap)  # frame by frame, in the same packets
    items = [item for group in expected.values() for item in group]
    kinds = [item[0] for item in items]
    assert kinds.count("crc_mismatch") == 2
    assert kinds.count("command") == 7
    assert kinds.count("/gimbal/attitude") == 2 and kinds.count("/gimbal/ranging") == 2
    text = json.dumps(packets)
    assert "gimbal.garbage" in text  # the noise is shown, not hidden
    assert "out of range" in text  # 100.01 deg/s is flagged as the decoder flags it


@pytest.mark.parametrize("sizes", [[1], [7, 3, 24, 50, 2]], ids=["byte-by-byte", "odd"])
def test_a_frame_cut_short_is_shown_once(lua: Path, tmp_path: Path, sizes: list[int]) -> None:
    pcap = _split_capture(tmp_path / "cut.pcap", sizes, cut_short=True)
    expected, packets = compare(lua, pcap, exact=False)
    items = [item for group in expected.values() for item in group]
    assert items.count(("incomplete",)) == 1
    assert json.dumps(packets).count('"gimbal.incomplete"') == 1


def _random_stream(rng: random.Random, to_idu: bool) -> bytes:
    """Frames of every kind with random contents, damaged frames and noise, glued."""
    rows = list(BY_CODE.values())
    can_ids = [*STATUS_FRAMES, CONTROL_ID, TEXT_ID, TEXT_END_ID, 0x18FEF100]
    parts: list[bytes] = []
    for _ in range(60):
        choice = rng.random()
        if choice < 0.1:
            noise = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 12)))
            parts.append(noise if rng.random() < 0.7 else b"\xeb\x90" + noise)
            continue
        data = bytearray(rng.randbytes(8))
        if rng.random() < 0.8:
            row = rng.choice(rows)
            data[0], data[1] = row.s_id, row.cmd
            if row.selector is not None and rng.random() < 0.8:
                data[row.selector.offset] = rng.choice(sorted(row.variants))
        if to_idu:
            if rng.random() < 0.7:
                frame = bytearray(wrap_control(bytes(data)))
            else:
                can_id = rng.choice(can_ids)
                frame = bytearray(wrap_can(can_id, bytes(data), with_crc=rng.random() < 0.5))
        else:
            layout = rng.choice(list(LAYOUTS.values()))
            message = bytearray(encode_attitude(pitch_deg=0, yaw_deg=0))
            message[2] = layout.length_byte
            message[16 : layout.crc_offset] = rng.randbytes(layout.crc_offset - 16)
            message[layout.crc_offset : layout.crc_offset + 2] = crc_bytes(
                message[: layout.crc_offset]
            )
            message[layout.frame_size :] = bytes(32 - layout.frame_size)
            frame = message if rng.random() < 0.7 else message[: layout.frame_size]
        roll = rng.random()
        if roll < 0.1:
            frame[rng.randrange(3, len(frame))] ^= 1 << rng.randrange(8)  # damaged
        elif roll < 0.15:
            frame = frame[: rng.randrange(3, len(frame) - 3)]  # cut short
        parts.append(bytes(frame))
    return b"".join(parts)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_random_streams_show_what_decode_gives(lua: Path, tmp_path: Path, seed: int) -> None:
    rng = random.Random(seed)
    sizes = [rng.randrange(1, 80) for _ in range(40)]
    streams = (_random_stream(rng, True), _random_stream(rng, False))
    pcap = _split_capture(tmp_path / "random.pcap", sizes, streams=streams)
    expected, _ = compare(lua, pcap, exact=False)
    assert sum(len(v) for v in expected.values()) > 60


def test_export_command_writes_the_dissector(tmp_path: Path) -> None:
    out = tmp_path / "gimbal.lua"
    run = subprocess.run(
        [*CLI, "export", "wireshark", "-o", str(out)],
        capture_output=True,
        text=True,
        encoding="utf-8",
    )
    assert run.returncode == 0, run.stderr
    assert out.read_text(encoding="utf-8") == lua_text()


@pytest.mark.slow
def test_the_port_is_a_preference(lua: Path, tmp_path: Path) -> None:
    moved = _split_capture(tmp_path / "moved.pcap", [200], port=3000)
    assert TSHARK is not None
    base = [TSHARK, "-n", "-X", f"lua_script:{lua}", "-r", str(moved)]
    default = subprocess.run(
        base, capture_output=True, text=True, timeout=60, encoding="utf-8"
    ).stdout
    assert "GIMBAL" not in default
    changed = subprocess.run(
        [*base, "-o", "gimbal.port:3000"],
        capture_output=True,
        text=True,
        timeout=60,
        encoding="utf-8",
    ).stdout
    assert "GIMBAL" in changed and "gimbal_control" in changed
