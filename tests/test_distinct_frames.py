"""A log in which every frame is different decodes to exactly the values that were sent.

Real traffic changes in every message (a stick moves, the gimbal turns, the UAV flies), so
no result may depend on bytes seen before: here no two frames of the log are alike, but
for the two feedback segments that hold only what the protocol fixes.
"""

from __future__ import annotations

import json
import random
from collections import Counter
from pathlib import Path
from typing import Any

import pytest

from analyzer.cli import main
from analyzer.protocol.codec import encode_command
from analyzer.protocol.feedback import encode_attitude, segments
from analyzer.protocol.ids import CONTROL_ID, FEEDBACK_ID, GPS_ID
from analyzer.protocol.uav import encode_gps

START = 1_715_680_800.0
ATTITUDE = encode_attitude(pitch_deg=0, yaw_deg=0)


def flight(seed: int = 7) -> tuple[list[str], list[tuple[str, dict[str, Any]]]]:
    """candump -L lines and, in order, the topic and values of each message sent."""
    rng = random.Random(seed)
    lines: list[str] = []
    sent: list[tuple[str, dict[str, Any]]] = []
    t = START
    pitch, yaw, motor = -30.0, 0.0, 0.0

    def line(can_id: int, data: bytes) -> None:
        nonlocal t
        t += 0.0005
        lines.append(f"({t:.6f}) can0 {can_id:08X}#{data.hex().upper()}")

    for block in range(200):
        for _ in range(9):  # a pilot's stick: speeds drawn at random
            pan, tilt = rng.randrange(-10000, 10001) / 100, rng.randrange(-10000, 10001) / 100
            line(
                CONTROL_ID, encode_command("gimbal_control", pan_speed_dps=pan, tilt_speed_dps=tilt)
            )
            sent.append(("/gimbal/command", {"pan_speed_dps": pan, "tilt_speed_dps": tilt}))
        box = {
            "x": rng.randrange(8192),
            "y": rng.randrange(8192),
            "width": 16 * rng.randrange(1, 256),
        }
        line(CONTROL_ID, encode_command("tracking", height=160, **box))
        sent.append(("/gimbal/command", {**box, "height": 160}))
        pitch = round(max(-90.0, min(30.0, pitch + rng.uniform(-3, 3))), 2)
        yaw = round((yaw + rng.uniform(0.01, 5)) % 360, 2)
        motor = round(max(-160.0, min(160.0, motor + rng.uniform(-4, 4))), 2)
        for part in segments(encode_attitude(pitch_deg=pitch, yaw_deg=yaw, motor_yaw_deg=motor)):
            line(FEEDBACK_ID, part)
        sent.append(
            ("/gimbal/attitude", {"pitch_deg": pitch, "yaw_deg": yaw, "motor_yaw_deg": motor})
        )
        for k in range(5):  # the UAV moves
            lat, lon = 31.12 + block * 1e-5 + k * 1e-7, 118.12 - block * 1e-5 - k * 1e-7
            line(GPS_ID, encode_gps(lat, lon))
            sent.append(
                ("/uav/gps", {"latitude_deg": round(lat, 7), "longitude_deg": round(lon, 7)})
            )
    return lines, sent


def test_the_log_has_no_two_frames_alike() -> None:
    lines, _ = flight()
    frames = [line.split(" ", 2)[2] for line in lines]
    # Only the first two segments of a feedback message are the same every time: the
    # header, the reserved bytes and the fixed id bytes. Every frame with a value differs.
    fixed = {frame for frame, count in Counter(frames).items() if count > 1}
    assert fixed == {f"030F0001#{part.hex().upper()}" for part in segments(ATTITUDE)[:2]}
    assert len(set(frames)) == len(frames) - 2 * 199 == 200 * (9 + 1 + 4 + 5) - 2 * 199


def test_every_distinct_frame_decodes_to_what_was_sent(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lines, sent = flight()
    path = tmp_path / "distinct.log"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    assert main(["decode", str(path), "--json"]) == 0
    events = [json.loads(text) for text in capsys.readouterr().out.splitlines()]
    assert [e["topic"] for e in events] == [topic for topic, _ in sent]
    for event, (_, values) in zip(events, sent, strict=True):
        assert event["warnings"] == []
        assert {name: event[name] for name in values} == pytest.approx(values, abs=1e-9)
    raws = [e["raw"] for e in events]
    assert len(set(raws)) == len(raws)
