"""Convert throughput (frames/s) against a bare mcap Writer.add_message loop, in the same run.

Writes a candump log of mixed gimbal traffic, converts it to MCAP the way
``gimbal-analyzer convert`` does (input reader, decoder, McapSink), and times a bare loop
of ``mcap.writer.Writer.add_message`` writing the same number of JSON messages. Each side
runs several times, interleaved, and the best time of each counts (the machine may be
busy). Both sides compress their chunks the same way (zstd by default, as recordings
are). Target: convert at no less than half the rate of the bare loop. It also reports the
recording's size against the same convert written uncompressed.

  python benchmarks/convert_speed.py [--frames 200000] [--repeat 3] [--compression zstd]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import random
import sys
import tempfile
import time
from pathlib import Path
from types import SimpleNamespace
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from analyzer.protocol.codec import encode_command
from analyzer.protocol.feedback import encode_attitude, encode_ranging
from analyzer.protocol.ids import (
    ALTITUDE_ID,
    CONTROL_ID,
    FEEDBACK_ID,
    GPS_ID,
    UAV_ATTITUDE_ID,
)
from analyzer.protocol.types import CanFrame
from analyzer.protocol.uav import encode_altitude, encode_gps, encode_uav_attitude

T0 = 1_700_000_000.0


def _feedback(t: float, message: bytes, step: float) -> list[CanFrame]:
    return [
        CanFrame(t + k * step, FEEDBACK_ID, message[8 * k : 8 * k + 8], channel="can0")
        for k in range(4)
    ]


def make_frames(count: int, *, gimbal_only: bool = False) -> list[CanFrame]:
    """Gimbal traffic (commands at 20 Hz, feedback at 2 Hz, UAV status at 10 Hz) whose values
    change from frame to frame as on a real bus: a pilot's stick (speeds drawn at random), a
    moving gimbal (attitude feedback follows the speeds), an aircraft flying an orbit (GPS,
    altitude and attitude move), ranging to a moving target; so no cache measures itself.

    By default padded with foreign IDs to a saturated 1 Mbit/s bus (about 7,600 frames/s,
    the mix of the live-load benchmark), each carrying a counter and sensor-like bytes that
    change every frame. ``gimbal_only``: protocol frames only, the worst case for convert
    since nearly every frame gives an event.
    """
    rng = random.Random(20240514)
    frames: list[CanFrame] = []
    step = 1 / 7600
    tick = 0
    pitch, yaw = -10.0, 0.0
    pan = tilt = 0.0
    while len(frames) < count:
        t = T0 + tick * 0.05  # one 50 ms slot
        if rng.random() < 0.1:  # the pilot moves the stick now and then, holds it between
            pan, tilt = rng.uniform(-99, 99), rng.uniform(-99, 99)
        pan_cmd = round(pan + rng.uniform(-0.5, 0.5), 2)  # a hand is never quite still
        tilt_cmd = round(tilt + rng.uniform(-0.5, 0.5), 2)
        data = encode_command("gimbal_control", pan_speed_dps=pan_cmd, tilt_speed_dps=tilt_cmd)
        slot = [CanFrame(t, CONTROL_ID, data, channel="can0")]
        yaw = (yaw + pan_cmd * 0.05) % 360
        pitch = min(60.0, max(-110.0, pitch + tilt_cmd * 0.05))
        if tick % 2 == 0:
            angle = tick * 0.0005  # an orbit of about 150 m
            lat = 31.1234567 + 0.00135 * math.sin(angle) + rng.uniform(-1e-6, 1e-6)
            lon = 118.1234567 + 0.00158 * math.cos(angle) + rng.uniform(-1e-6, 1e-6)
            slot.append(CanFrame(t, GPS_ID, encode_gps(lat, lon), channel="can0"))
            altitude = 100 + 5 * math.sin(tick / 300) + rng.uniform(-0.05, 0.05)
            slot.append(CanFrame(t, ALTITUDE_ID, encode_altitude(altitude), channel="can0"))
            heading = (math.degrees(angle) + 270) % 360 - 180  # -180..180 fits the field
            attitude = encode_uav_attitude(
                rng.uniform(-3, 3), rng.uniform(-8, -4), round(heading, 1)
            )
            slot.append(CanFrame(t, UAV_ATTITUDE_ID, attitude, channel="can0"))
        if tick % 10 == 3:
            motor = ((yaw + 180) % 360) - 180
            motor = min(170.0, max(-170.0, motor))
            message = encode_attitude(pitch_deg=round(pitch, 2), yaw_deg=yaw, motor_yaw_deg=motor)
            slot += _feedback(t, message, step)
        if tick % 10 == 8:
            ranging = encode_ranging(
                distance_m=round(rng.uniform(50, 1500), 1),
                height_m=round(rng.uniform(5, 120), 1),
                latitude_deg=31.1 + rng.uniform(-0.01, 0.01),
                longitude_deg=118.1 + rng.uniform(-0.01, 0.01),
            )
            slot += _feedback(t, ranging, step)
        if not gimbal_only:
            for k in range(380 - len(slot)):
                ident = 0x18FF0000 + k % 64
                counter = (tick * 380 + k) & 0xFFFF
                payload = counter.to_bytes(2, "little") + rng.randbytes(6)
                slot.append(CanFrame(t + k * step, ident, payload, channel="can0"))
        slot.sort(key=lambda fr: fr.time)
        frames.extend(slot)
        tick += 1
    return frames[:count]


def write_candump(frames: list[CanFrame], path: Path) -> None:
    with open(path, "w", encoding="utf-8") as f:
        for fr in frames:
            ident = f"{fr.can_id:08X}" if fr.extended else f"{fr.can_id:03X}"
            f.write(f"({fr.time:.6f}) {fr.channel} {ident}#{fr.data.hex().upper()}\n")


def run_convert(
    source_path: Path, frames: list[CanFrame], out: Path, compression: str
) -> tuple[float, Any, str]:
    from analyzer.mcapio.write.sink import McapSink, recording_metadata
    from analyzer.pipeline import Pipeline, run_items

    open_input: Any = None
    try:
        import analyzer.inputs as inputs_module

        open_input = getattr(inputs_module, "open_input", None)
    except ImportError:
        pass
    started = time.perf_counter()
    if open_input is not None:
        items: Any = open_input(str(source_path))
        how = "candump file through analyzer.inputs"
    else:
        items = frames
        how = "in-memory frames (analyzer.inputs not available: input parsing not measured)"
    sink = McapSink(
        out, metadata=recording_metadata("bench"), flush_interval=None, compression=compression
    )
    pipeline = Pipeline([sink])
    run_items(items, pipeline)  # closes the sink
    tally = pipeline.tally
    result = SimpleNamespace(
        messages=sink.messages_written, frames=tally.frames, events=tally.events
    )
    return time.perf_counter() - started, result, how


def run_bare(count: int, out: Path, *, encode: bool, compression: str) -> float:
    """``count`` JSON messages through mcap.writer.Writer.add_message, nothing else."""
    from mcap.writer import CompressionType, Writer

    body = {
        "time": T0,
        "id": CONTROL_ID,
        "extended": True,
        "dlc": 8,
        "data": "0F 04 0C FE 00 00 00 00",
        "channel": "can0",
    }
    fixed = json.dumps(body).encode()
    started = time.perf_counter()
    with open(out, "wb") as f:
        writer = Writer(f, chunk_size=128 * 1024, compression=CompressionType[compression.upper()])
        writer.start()
        schema = writer.register_schema("frame", "jsonschema", b'{"type":"object"}')
        channel = writer.register_channel("/can/frames", "json", schema)
        for i in range(count):
            stamp = 1_700_000_000_000_000_000 + i * 131_000
            if encode:
                body["time"] = stamp / 1e9
                data = json.dumps(body).encode()
            else:
                data = fixed
            writer.add_message(channel, stamp, data, stamp)
        writer.finish()
    return time.perf_counter() - started


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=200_000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--compression", choices=("zstd", "lz4", "none"), default="zstd")
    args = parser.parse_args()
    for gimbal_only, title in (
        (False, "saturated bus: gimbal traffic among foreign IDs (the live-load mix)"),
        (True, "gimbal traffic only: nearly every frame gives an event (worst case)"),
    ):
        print(f"== {title}")
        scenario(make_frames(args.frames, gimbal_only=gimbal_only), args.repeat, args.compression)
        print()
    return 0


def scenario(frames: list[CanFrame], repeat: int, compression: str) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        log = folder / "traffic.log"
        write_candump(frames, log)
        convert_times: list[float] = []
        bare_times: list[float] = []
        bare_fixed: list[float] = []
        result: Any = None
        how = ""
        for _ in range(repeat):
            seconds, result, how = run_convert(log, frames, folder / "converted.mcap", compression)
            convert_times.append(seconds)
            bare = folder / "bare.mcap"
            bare_times.append(run_bare(len(frames), bare, encode=True, compression=compression))
            fixed = folder / "bare2.mcap"
            bare_fixed.append(run_bare(len(frames), fixed, encode=False, compression=compression))
        size = os.path.getsize(folder / "converted.mcap")
        run_convert(log, frames, folder / "plain.mcap", "none")
        plain = os.path.getsize(folder / "plain.mcap")
    n = len(frames)
    convert_rate = n / min(convert_times)
    bare_rate = n / min(bare_times)
    fixed_rate = n / min(bare_fixed)
    ratio = convert_rate / bare_rate
    print(f"input: {n} CAN frames ({how})")
    print(
        f"convert:  {convert_rate:12,.0f} frames/s   "
        f"({result.messages} MCAP messages: {result.frames} raw frames + {result.events} events "
        f"+ Foxglove views)"
    )
    print(
        f"file size: {size / 1e6:.2f} MB {compression} vs {plain / 1e6:.2f} MB uncompressed "
        f"({plain / size:.1f}x smaller)"
    )
    print(
        f"bare loop: {bare_rate:11,.0f} messages/s  (json.dumps + Writer.add_message, {n} messages)"
    )
    print(f"           {fixed_rate:11,.0f} messages/s  (Writer.add_message of pre-encoded bytes)")
    verdict = "met" if ratio >= 0.5 else "NOT met"
    print(f"ratio convert / bare loop: {ratio:.2f} (target >= 0.50: {verdict})")
    print(f"ratio convert / pre-encoded loop: {convert_rate / fixed_rate:.2f}")
    print(f"best of {repeat} runs each, interleaved; {compression} chunks on both sides")


if __name__ == "__main__":
    raise SystemExit(main())
