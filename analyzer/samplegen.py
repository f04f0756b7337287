"""Writes the sample captures of ``samples/`` from the protocol's own encoders, deterministically.

    python -m analyzer.samplegen samples/

gives the same bytes every time: a candump -L flight log, a pcap of a TCP session
with the IDU and a UART byte dump, each with a few deliberate faults (listed in
``EXPECTED_DIAGNOSTICS`` and in samples/README.md), and a candump -L log of a ground
station driving the simulated gimbal like a pilot (``analyzer.sim.pilot_session``).
"""

from __future__ import annotations

import argparse
import math
import random
import socket
import struct
from collections.abc import Callable
from pathlib import Path
from typing import Any

from analyzer.protocol.codec import encode_command
from analyzer.protocol.feedback import encode_attitude, encode_ranging, segments
from analyzer.protocol.framing import wrap_can, wrap_control
from analyzer.protocol.ids import (
    ALTITUDE_ID,
    CONTROL_ID,
    FEEDBACK_ID,
    GPS_ID,
    TCP_PORT,
    UAV_ATTITUDE_ID,
)
from analyzer.protocol.types import BAD_LINE, CRC_MISMATCH, GARBAGE, INCOMPLETE
from analyzer.protocol.uav import encode_altitude, encode_gps, encode_text, encode_uav_attitude
from analyzer.sim.pilot_session import pilot_log

CANDUMP_NAME = "flight-candump.log"
PCAP_NAME = "idu-tcp.pcap"
UART_NAME = "uart-dump.bin"
PILOT_NAME = "pilot-candump.log"

START = 1715680800.0  # 2024-05-14 10:00:00 UTC
HOME = (31.1234567, 118.1234567)  # the vendor document's example position
FLIGHT_S = 20.0
CHANNEL = "can0"

# Diagnostics each sample is meant to produce (kind -> count); anything else is a bug.
EXPECTED_DIAGNOSTICS: dict[str, dict[str, int]] = {
    CANDUMP_NAME: {CRC_MISMATCH: 1, INCOMPLETE: 1, BAD_LINE: 1},
    PCAP_NAME: {},
    UART_NAME: {GARBAGE: 4, CRC_MISMATCH: 1},
    PILOT_NAME: {},
}
# Commands with an unknown CMD (decoded as name "unknown" with a warning).
EXPECTED_UNKNOWN_COMMANDS = {CANDUMP_NAME: 1, PCAP_NAME: 0, UART_NAME: 0, PILOT_NAME: 0}

# The vendor document's "One key to down" TCP example: one zero byte too many (erratum).
DOCUMENT_LOOK_DOWN_25 = bytes.fromhex(
    "EB 90 0A 00 00 00 00 00 00 00 00 00 00 40 88 0F 07 00 00 00 00 00 00 68 5E"
)


def flight_path(t: float) -> dict[str, float]:
    """Where the UAV is ``t`` seconds into the flight: a slow climbing turn."""
    angle = t / FLIGHT_S * math.pi / 2
    return {
        "latitude_deg": round(HOME[0] + 0.0004 * math.sin(angle), 7),
        "longitude_deg": round(HOME[1] + 0.0004 * (1 - math.cos(angle)), 7),
        "altitude_m": round(50.0 + 2.5 * t, 2),
        "pitch_deg": round(2.0 * math.sin(t), 2),
        "roll_deg": round(-4.0 + 1.5 * math.cos(t / 2), 2),
        "yaw_deg": round((90.0 + t * 4.5) % 360, 2),
    }


def uav_attitude(position: dict[str, float]) -> bytes:
    return encode_uav_attitude(position["pitch_deg"], position["roll_deg"], position["yaw_deg"])


def gimbal_pose(t: float) -> dict[str, float]:
    """The gimbal's attitude at ``t``: panning left during the first command burst."""
    pan = -5.0 * min(max(t - 2.0, 0.0), 1.0)
    return {
        "pitch_deg": round(-30.0 + 5 * math.sin(t / 4), 2),
        "yaw_deg": round((135.0 + pan) % 360, 2),
        "motor_yaw_deg": round(pan, 2),
    }


def command_script() -> list[tuple[float, bytes]]:
    """(seconds into the flight, 8 CAN bytes) of the ground station's commands."""
    script: list[tuple[float, bytes]] = []

    def at(t: float, name: str, **params: Any) -> None:
        script.append((t, encode_command(name, **params)))

    # Turn left at 5 deg/s for one second (repeated every 50 ms), then stop.
    for i in range(20):
        at(2.0 + i * 0.05, "gimbal_control", pan_speed_dps=-5.0, tilt_speed_dps=0)
    at(3.0, "gimbal_control", pan_speed_dps=0, tilt_speed_dps=0)
    at(4.0, "specified_angle", pitch_deg=-45)
    at(4.5, "specified_angle", yaw_deg=45)
    at(5.0, "specified_angle", zoom=10)
    at(6.0, "zoom", action="zoom_in")
    at(6.8, "zoom", action="stop")
    at(7.2, "focus", action="auto_focus")
    at(8.0, "snapshot", mode="single")
    at(8.5, "snapshot", mode="continuous", shots=3)
    at(9.0, "recording", action="start")
    at(10.0, "tracking", x=4096, y=4096, width=320, height=240)
    at(11.5, "tracking_stop")
    at(12.0, "tap_zoom", x_pct=25.0, y_pct=-10.0)
    at(12.5, "tap_focus", x=2000, y=3000)
    at(13.0, "palette", palette="iron_red")
    at(13.3, "pip_cycle")
    at(13.6, "digital_zoom", action="zoom_in")
    at(14.0, "gimbal_control", s_id=0x1F, pan_speed_dps=10.0, tilt_speed_dps=-2.5)
    at(14.1, "gimbal_control", s_id=0x1F, pan_speed_dps=0, tilt_speed_dps=0)
    at(15.0, "zoom_1x")
    at(16.0, "look_down")
    at(17.0, "forward")
    at(18.0, "recording", action="stop")
    at(18.5, "quick_calibration")
    return sorted(script, key=lambda item: item[0])


def feedback_message(slot: int, t: float) -> bytes:
    """The gimbal's 32-byte message of a 500 ms slot: attitude, ranging every 4th slot."""
    if slot % 4 == 3:
        position = flight_path(t)
        return encode_ranging(
            distance_m=round(180.0 + slot * 0.5, 1),
            height_m=round(position["altitude_m"], 1),
            latitude_deg=round(position["latitude_deg"] + 0.0012, 7),
            longitude_deg=round(position["longitude_deg"] + 0.0009, 7),
            success=True,
        )
    pose = gimbal_pose(t)
    return encode_attitude(
        pitch_deg=pose["pitch_deg"],
        yaw_deg=pose["yaw_deg"],
        motor_yaw_deg=pose["motor_yaw_deg"],
        gimbal_type=1,
        tracking=10 <= t < 11.5,
    )


# -- candump -L flight log ---------------------------------------------------------------------


def candump_log() -> bytes:
    """A flight seen on the CAN bus, with every message kind and four faults."""
    frames: list[tuple[float, int, bytes]] = []  # (time, id, data)
    steps = int(FLIGHT_S * 5)
    for i in range(steps):  # UAV status at 5 Hz, staggered
        t = i * 0.2
        p = flight_path(t)
        frames.append((t + 0.010, GPS_ID, encode_gps(p["latitude_deg"], p["longitude_deg"])))
        frames.append((t + 0.020, ALTITUDE_ID, encode_altitude(p["altitude_m"])))
        frames.append(
            (
                t + 0.030,
                UAV_ATTITUDE_ID,
                encode_uav_attitude(p["pitch_deg"], p["roll_deg"], p["yaw_deg"]),
            )
        )
        # Traffic of other devices on the same bus (decoded only with --raw).
        frames.append((t + 0.050, 0x18FEF100, bytes([i & 0xFF, 0x10, 0x27, 0, 0, 0, 0xFF, 0xFF])))
        if i % 5 == 0:
            frames.append((t + 0.070, 0x0CFE6CEE, bytes([0x64, 0x32, i & 0xFF, 0x00])))
    for slot in range(int(FLIGHT_S * 2)):  # gimbal feedback at 2 Hz, four segments 1 ms apart
        t = 0.25 + slot * 0.5
        parts = segments(feedback_message(slot, t))
        if slot == 13:  # fault: a segment corrupted on the bus (CRC mismatch)
            parts[2] = bytes([parts[2][0] ^ 0x20]) + parts[2][1:]
        if slot == 27:  # fault: a segment lost (incomplete message)
            parts = parts[:1] + parts[2:]
        for k, part in enumerate(parts):
            frames.append((t + k * 0.001, FEEDBACK_ID, part))
    for t, data in command_script():
        frames.append((t + 0.004, CONTROL_ID, data))
    frames.append((9.504, CONTROL_ID, bytes.fromhex("0F 77 01 00 00 00 00 00")))  # fault: unknown
    for k, (can_id, data) in enumerate(encode_text("ARMED, TAKEOFF AT 10:00, ALT HOLD 100 M")):
        frames.append((1.1 + k * 0.002, can_id, data))
    frames.sort(key=lambda f: f[0])
    lines = [
        f"({START + t:.6f}) {CHANNEL} {can_id:08X}#{data.hex().upper()}"
        for t, can_id, data in frames
    ]
    # Fault: the logger was stopped in the middle of writing its last line.
    lines.append(f"({START + FLIGHT_S:.6f}) {CHANNEL} 0000FF15#128D1")
    return ("\n".join(lines)).encode("ascii")


# -- pcap of a TCP session with the IDU --------------------------------------------------------

CLIENT = ("192.168.42.10", 50312)
IDU = ("192.168.42.200", TCP_PORT)
MAC_CLIENT = bytes.fromhex("02 00 00 00 00 0a")
MAC_IDU = bytes.fromhex("02 00 00 00 00 c8")
TCP_FLAGS = {"F": 0x01, "S": 0x02, "P": 0x08, "A": 0x10}


def _checksum(data: bytes) -> int:
    if len(data) % 2:
        data += b"\0"
    total = sum(struct.unpack(f"!{len(data) // 2}H", data))
    while total >> 16:
        total = (total & 0xFFFF) + (total >> 16)
    return ~total & 0xFFFF


def _packet(to_idu: bool, seq: int, ack: int, flags: str, payload: bytes, ident: int) -> bytes:
    (src, sport), (dst, dport) = (CLIENT, IDU) if to_idu else (IDU, CLIENT)
    bits = sum(TCP_FLAGS[f] for f in flags)
    tcp = struct.pack("!HHIIBBHHH", sport, dport, seq, ack, 5 << 4, bits, 64240, 0, 0) + payload
    pseudo = socket.inet_aton(src) + socket.inet_aton(dst) + struct.pack("!BBH", 0, 6, len(tcp))
    tcp = tcp[:16] + struct.pack("!H", _checksum(pseudo + tcp)) + tcp[18:]
    ip = struct.pack(
        "!BBHHHBBH4s4s",
        0x45,
        0,
        20 + len(tcp),
        ident,
        0x4000,
        64,
        6,
        0,
        socket.inet_aton(src),
        socket.inet_aton(dst),
    )
    ip = ip[:10] + struct.pack("!H", _checksum(ip)) + ip[12:]
    macs = MAC_IDU + MAC_CLIENT if to_idu else MAC_CLIENT + MAC_IDU
    return macs + b"\x08\x00" + ip + tcp


def idu_pcap() -> bytes:
    """A ground station talking to the IDU over TCP port 2000, both directions.

    Commands (0x0A) and forwarded UAV status (0x0B, CRC not set) go to the IDU; the
    IDU answers with feedback frames at 2 Hz. The capture shows glued frames, a frame
    split over two segments, two segments captured out of order and a retransmission,
    all of which reassemble cleanly.
    """
    packets: list[tuple[float, bytes]] = []
    seq = {True: 1_000_000, False: 3_000_000_000}  # client ISN, IDU ISN
    ident = {True: 100, False: 5000}

    def send(
        t: float, to_idu: bool, payload: bytes, flags: str = "PA", at_seq: int | None = None
    ) -> None:
        start = seq[to_idu] if at_seq is None else at_seq
        ident[to_idu] += 1
        other = seq[not to_idu]
        packets.append((t, _packet(to_idu, start, other, flags, payload, ident[to_idu])))
        if at_seq is None:
            seq[to_idu] += len(payload) + (1 if ("S" in flags or "F" in flags) else 0)

    # Handshake.
    packets.append((0.000, _packet(True, seq[True], 0, "S", b"", 100)))
    seq[True] += 1
    packets.append((0.001, _packet(False, seq[False], seq[True], "SA", b"", 5000)))
    seq[False] += 1
    send(0.002, True, b"", "A")

    merged = _idu_stream()
    for index, (t, to_idu, data) in enumerate(merged):
        t += 0.01
        if index == 30:  # one frame split over two segments
            send(t, to_idu, data[:9])
            send(t + 0.002, to_idu, data[9:])
        elif index == 45:  # two segments captured out of order
            first = seq[to_idu]
            send(t + 0.003, to_idu, data[12:], at_seq=first + 12)
            send(t, to_idu, data[:12], at_seq=first)
            seq[to_idu] += len(data)
        elif index == 60:  # a retransmission of the same bytes
            first = seq[to_idu]
            send(t, to_idu, data)
            send(t + 0.2, to_idu, data, at_seq=first)
        else:
            send(t, to_idu, data)
        if index % 10 == 9:  # the other side acknowledges now and then
            send(t + 0.001, not to_idu, b"", "A")
    send(FLIGHT_S + 0.1, True, b"", "FA")
    send(FLIGHT_S + 0.101, False, b"", "FA")
    send(FLIGHT_S + 0.102, True, b"", "A")
    packets.sort(key=lambda p: p[0])

    return _pcap_file(packets)


def _idu_stream() -> list[tuple[float, bool, bytes]]:
    """The link's frames by time and direction (True: to the IDU): the ground station's
    commands and forwarded UAV status, the IDU's feedback at 2 Hz; frames sent at the same
    moment in the same direction glued into one segment."""
    stream: list[tuple[float, bool, bytes]] = []
    for t, data in command_script():
        stream.append((t, True, wrap_control(data)))
    for i in range(int(FLIGHT_S)):  # forwarded UAV status at 1 Hz
        p = flight_path(float(i))
        stream.append(
            (i + 0.6, True, wrap_can(GPS_ID, encode_gps(p["latitude_deg"], p["longitude_deg"])))
        )
        stream.append((i + 0.6, True, wrap_can(ALTITUDE_ID, encode_altitude(p["altitude_m"]))))
    for slot in range(int(FLIGHT_S * 2)):
        t = 0.25 + slot * 0.5
        stream.append((t, False, feedback_message(slot, t)))
    stream.sort(key=lambda s: (s[0], not s[1]))
    merged: list[tuple[float, bool, bytes]] = []
    for t, to_idu, data in stream:
        if merged and merged[-1][0] == t and merged[-1][1] == to_idu:
            merged[-1] = (t, to_idu, merged[-1][2] + data)
        else:
            merged.append((t, to_idu, data))
    return merged


def _pcap_file(packets: list[tuple[float, bytes]]) -> bytes:
    """Ethernet packets (seconds after START, bytes) as a classic pcap file."""
    header = struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1)  # Ethernet
    out = [header]
    for t, frame in packets:
        when = START + t
        sec = int(when)
        usec = round((when - sec) * 1e6)
        out.append(struct.pack("<IIII", sec, usec, len(frame), len(frame)) + frame)
    return b"".join(out)


# -- UART byte dump ----------------------------------------------------------------------------


def uart_dump() -> bytes:
    """Bytes on the connector's UART pins: control and 0x0B frames with line noise.

    Faults: noise before the first frame, noise between two frames, the vendor
    document's 25-byte "One key to down" example (one zero too many) and noise after.
    """
    rng = random.Random(2000)
    noise: Callable[[int], bytes] = lambda n: bytes(rng.randrange(1, 0xEB) for _ in range(n))  # noqa: E731
    out = bytearray(noise(7))
    for i, (_t, data) in enumerate(command_script()[19:]):
        out += wrap_control(data)
        if i == 3:
            out += noise(5)
        if i % 4 == 0:
            p = flight_path(float(i))
            out += wrap_can(GPS_ID, encode_gps(p["latitude_deg"], p["longitude_deg"]))
            out += wrap_can(
                UAV_ATTITUDE_ID, encode_uav_attitude(p["pitch_deg"], p["roll_deg"], p["yaw_deg"])
            )
        if i == 10:
            out += DOCUMENT_LOOK_DOWN_25
    out += wrap_control(encode_command("look_down"))
    out += noise(3)
    return bytes(out)


WRITERS: dict[str, Callable[[], bytes]] = {
    CANDUMP_NAME: candump_log,
    PCAP_NAME: idu_pcap,
    UART_NAME: uart_dump,
    PILOT_NAME: pilot_log,
}


def write_samples(folder: str | Path) -> list[Path]:
    """Write every sample file into ``folder``; returns their paths."""
    target = Path(folder)
    target.mkdir(parents=True, exist_ok=True)
    written = []
    for name, make in WRITERS.items():
        path = target / name
        path.write_bytes(make())
        written.append(path)
    return written


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m analyzer.samplegen", description="Write the sample capture files."
    )
    parser.add_argument("folder", nargs="?", default="samples", help="where to write them")
    args = parser.parse_args(argv)
    for path in write_samples(args.folder):
        print(f"{path}  {path.stat().st_size:,} bytes")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
