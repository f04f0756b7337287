"""Deterministic capture files full of odd and damaged traffic, as a hostile test corpus has.

``write_fault_logs(folder)`` writes the same bytes every time (a seeded generator and the
protocol's own encoders): a candump -L log and a raw TCP/UART byte dump. Every command
row of the table with random data bytes, values out of range, unknown selectors, labels
and components, short, long, FD, remote, standard-ID and error frames, feedback messages
that change every time with every fault of the reassembler, status frames, text
messages, and frames of other devices on two channels.
"""

from __future__ import annotations

import random
from pathlib import Path

from analyzer.protocol.codec import encode_command
from analyzer.protocol.command_table import COMMANDS
from analyzer.protocol.crc import crc_bytes
from analyzer.protocol.feedback import encode_attitude, encode_ranging, segments
from analyzer.protocol.framing import wrap_can, wrap_control
from analyzer.protocol.ids import (
    ALTITUDE_ID,
    CONTROL_ID,
    FEEDBACK_ID,
    GPS_ID,
    TEXT_END_ID,
    TEXT_ID,
    UAV_ATTITUDE_ID,
)
from analyzer.protocol.uav import encode_gps, encode_text

CANDUMP_NAME = "faults-candump.log"
STREAM_NAME = "faults-stream.bin"
START = 1_715_680_800.0
STATUS_IDS = (GPS_ID, ALTITUDE_ID, UAV_ATTITUDE_ID)
SNAPSHOTS = [
    ("single", ""),
    ("continuous", "shots"),
    ("time_lapse", "delay_s"),
    ("timed", "timer_s"),
    ("stop", ""),
]


class _Log:
    """candump -L lines with a clock that moves on by a random step per frame."""

    def __init__(self, rng: random.Random) -> None:
        self.rng = rng
        self.time = START
        self.lines: list[str] = []

    def add(self, can_id: int, data: bytes, *, channel: str = "can0", step: float = 0.0) -> None:
        self.time += step or self.rng.randrange(1, 4000) / 1_000_000
        text = f"{can_id:08X}" if can_id > 0x7FF or self.rng.random() < 0.9 else f"{can_id:03X}"
        self.lines.append(f"({self.time:.6f}) {channel} {text}#{data.hex().upper()}")

    def raw(self, body: str) -> None:
        self.time += 0.001
        self.lines.append(f"({self.time:.6f}) can0 {body}")


def _random_command(rng: random.Random) -> bytes:
    """A command of the table with random data bytes, often mostly zero."""
    row = rng.choice(COMMANDS)
    data = bytearray(rng.getrandbits(8) for _ in range(8))
    data[0], data[1] = row.s_id, row.cmd
    for i in range(2, 8):
        if rng.random() < 0.4:
            data[i] = 0
    if row.selector is not None and rng.random() < 0.8:
        data[row.selector.offset] = rng.choice([*row.variants, rng.getrandbits(8)])
    return bytes(data)


def _valid_commands(rng: random.Random) -> list[bytes]:
    """Well-formed commands with values drawn in range, and some just outside."""
    out = []
    for _ in range(300):
        pan, tilt = rng.randrange(-10000, 10001) / 100, rng.randrange(-10000, 10001) / 100
        out.append(encode_command("gimbal_control", pan_speed_dps=pan, tilt_speed_dps=tilt))
        out.append(
            encode_command(
                "gimbal_control",
                s_id="dual_sensor",
                pan_speed_dps=pan * 1.5,
                tilt_speed_dps=-tilt * 1.5,
                check_range=False,
            )
        )
    for _ in range(60):
        out.append(
            encode_command(
                "specified_angle", yaw_deg=rng.randrange(-100, 3700) / 10, check_range=False
            )
        )
        out.append(
            encode_command(
                "specified_angle", pitch_deg=rng.randrange(-1100, 700) / 10, check_range=False
            )
        )
        out.append(
            encode_command("specified_angle", zoom=rng.randrange(50, 3600) / 100, check_range=False)
        )
        out.append(
            encode_command(
                "tap_zoom",
                x_pct=rng.uniform(-110, 110),
                y_pct=rng.uniform(-110, 110),
                check_range=False,
            )
        )
        out.append(
            encode_command(
                "tracking",
                x=rng.randrange(0, 9000),
                y=rng.randrange(0, 9000),
                width=rng.randrange(0, 4000),
                height=rng.randrange(0, 4000),
                check_range=False,
            )
        )
        out.append(
            encode_command(
                "tap_focus",
                x=rng.randrange(0, 9000),
                y=rng.randrange(0, 9000),
                width=rng.choice([400, 416]),
                height=rng.choice([400, 384]),
                check_range=False,
            )
        )
        mode, extra = rng.choice(SNAPSHOTS)
        if extra:
            out.append(encode_command("snapshot", mode=mode, **{extra: rng.randrange(256)}))
        else:
            out.append(encode_command("snapshot", mode=mode))
        out.append(encode_command("palette", palette=rng.randrange(0, 20), check_range=False))
    return out


def _feedback(rng: random.Random, n: int) -> bytes:
    if n % 5 == 4:
        return encode_ranging(
            distance_m=rng.randrange(0, 65535) / 10,
            height_m=rng.randrange(-3000, 3000) / 10,
            latitude_deg=rng.uniform(-95, 95),
            longitude_deg=rng.uniform(-185, 185),
            success=rng.random() < 0.8,
            check_range=False,
        )
    return encode_attitude(
        pitch_deg=rng.randrange(-11500, 6500) / 100,
        yaw_deg=rng.randrange(0, 36500) / 100,
        motor_yaw_deg=rng.randrange(-32700, 32700) / 100,
        gimbal_type=rng.choice([1, 2, 3, 4, 5, 6, 7]),
        tracking=rng.random() < 0.3,
        control_mode=rng.choice([1, 2, 3, 9]),
        check_range=False,
    )


def _odd_feedback(rng: random.Random, message: bytes) -> bytes:
    """A message with reserved bytes, id bytes or padding that are not what they should be."""
    data = bytearray(message)
    size = 27 if data[2] == 0x0C else 31
    where = rng.choice([3, 7, 11, 12, 14])
    data[where] ^= 1 + rng.getrandbits(7)
    data[size - 2 : size] = crc_bytes(bytes(data[: size - 2]))
    if rng.random() < 0.5 and size < 32:
        data[31] = 0x55
    return bytes(data)


def _feedback_run(log: _Log, rng: random.Random, message: bytes, channel: str) -> None:
    parts = segments(message)
    fault = rng.randrange(12)
    if fault == 0:  # one segment lost
        del parts[rng.randrange(4)]
    elif fault == 1:  # one bit flipped
        k = rng.randrange(1, 4)
        part = bytearray(parts[k])
        part[rng.randrange(8)] ^= 1 << rng.randrange(8)
        parts[k] = bytes(part)
    elif fault == 2:  # one segment sent twice
        k = rng.randrange(4)
        parts.insert(k, parts[k])
    elif fault == 3:  # a short last segment
        parts[3] = parts[3][: rng.randrange(0, 8)]
    for i, part in enumerate(parts):
        late = fault == 4 and i == 2
        log.add(FEEDBACK_ID, part, channel=channel, step=0.35 if late else 0.0)
    if fault == 5:  # a stale partial message: the next one comes much later
        log.add(FEEDBACK_ID, parts[0], channel=channel)
        log.time += 1.5


def candump_lines(seed: int = 22) -> list[str]:
    """The candump -L fault log, line by line."""
    rng = random.Random(seed)
    log = _Log(rng)
    valid = _valid_commands(rng)
    texts = [*encode_text("BATTERY 40 %, RTH"), *encode_text("GPS LOST"), *encode_text("")]
    for n in range(1200):
        channel = "can1" if rng.random() < 0.2 else "can0"
        pick = rng.random()
        if pick < 0.25:
            log.add(CONTROL_ID, _random_command(rng), channel=channel)
        elif pick < 0.45:
            log.add(CONTROL_ID, valid[rng.randrange(len(valid))], channel=channel)
        elif pick < 0.47:
            data = bytes([rng.choice([0x0F, 0x1F, 0x2F]), rng.getrandbits(8)])
            log.add(CONTROL_ID, data + bytes(rng.getrandbits(8) for _ in range(6)))
        elif pick < 0.50:  # short or empty command frames
            log.add(CONTROL_ID, valid[rng.randrange(len(valid))][: rng.randrange(0, 8)])
        elif pick < 0.66:
            message = _feedback(rng, n)
            if rng.random() < 0.1:
                message = _odd_feedback(rng, message)
            _feedback_run(log, rng, message, channel)
        elif pick < 0.70:  # a stray segment
            log.add(FEEDBACK_ID, bytes(rng.getrandbits(8) for _ in range(rng.randrange(9))))
        elif pick < 0.80:
            can_id = rng.choice(STATUS_IDS)
            if can_id == GPS_ID and rng.random() < 0.5:
                data = encode_gps(rng.uniform(-90, 90), rng.uniform(-180, 180))
            else:
                data = bytes(rng.getrandbits(8) for _ in range(rng.choice([8, 8, 8, 3, 6, 0])))
            log.add(can_id, data, channel=channel)
        elif pick < 0.83:
            for can_id, data in texts[rng.randrange(len(texts)) :][: rng.randrange(1, 4)]:
                log.add(can_id, data, channel=channel)
        elif pick < 0.86:
            if rng.random() < 0.5:
                log.add(TEXT_ID, bytes([0xC3, 0xA9, 7, 65, 66, 0, 0, 0]), channel=channel)
                log.add(TEXT_END_ID, b"\x80END", channel=channel)
            else:
                log.add(
                    rng.choice([TEXT_ID, TEXT_END_ID]), bytes(rng.getrandbits(8) for _ in range(8))
                )
        elif pick < 0.90:  # flags: remote, FD, error frames, standard IDs on protocol IDs
            can_id = rng.choice([CONTROL_ID, FEEDBACK_ID, GPS_ID, TEXT_ID, 0x123])
            kind = rng.randrange(4)
            if kind == 0:
                log.raw(f"{can_id:08X}#R")
            elif kind == 1:
                log.raw(f"{can_id:08X}##1{valid[rng.randrange(len(valid))].hex().upper()}01020304")
            elif kind == 2:
                log.raw(f"{0x20000000 | rng.getrandbits(8):08X}#0000000000000000")
            else:
                log.raw(f"{can_id & 0x7FF:03X}#{valid[rng.randrange(len(valid))].hex().upper()}")
        elif pick < 0.92:
            log.raw(rng.choice(["damaged line", "00000F01#0F0", "030F0001#ZZ", "#"]))
        else:
            foreign = rng.choice([0x18FEF100, 0x0CF00400, 0x123, 0x7E8])
            log.add(
                foreign, bytes(rng.getrandbits(8) for _ in range(rng.randrange(9))), channel=channel
            )
    return log.lines


def stream_bytes(seed: int = 23) -> bytes:
    """A TCP/UART byte dump: control frames, forwarded CAN frames, feedback and noise."""
    rng = random.Random(seed)
    valid = _valid_commands(rng)
    out = bytearray()
    for n in range(400):
        pick = rng.random()
        if pick < 0.35:
            data = _random_command(rng) if rng.random() < 0.5 else valid[rng.randrange(len(valid))]
            frame = bytearray(wrap_control(data))
            if rng.random() < 0.05:
                frame[rng.randrange(3, 24)] ^= 0x10
            out += frame
        elif pick < 0.55:
            can_id = rng.choice([*STATUS_IDS, CONTROL_ID, TEXT_ID, TEXT_END_ID, 0x18FEF100])
            data = bytes(rng.getrandbits(8) for _ in range(rng.choice([8, 8, 4])))
            out += wrap_can(can_id, data, with_crc=rng.random() < 0.5)
        elif pick < 0.80:
            message = _feedback(rng, n)
            size = 27 if message[2] == 0x0C else 31
            out += message[:size] if rng.random() < 0.5 else message
        else:
            out += bytes(rng.getrandbits(8) for _ in range(rng.randrange(1, 12)))
    return bytes(out)


def write_fault_logs(folder: Path) -> list[Path]:
    """Write both files into ``folder``; returns their paths."""
    candump = folder / CANDUMP_NAME
    candump.write_text("\n".join(candump_lines()) + "\n", encoding="utf-8")
    stream = folder / STREAM_NAME
    stream.write_bytes(stream_bytes())
    return [candump, stream]
