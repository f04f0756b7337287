"""Decode speed: ``gimbal-analyzer decode --summary`` against python-can's LogReader, same file.

    python benchmarks/decode_speed.py [--frames 1000000] [--keep DIR]

Writes a candump -L log of a busy drone CAN bus (gimbal protocol traffic mixed with
ESCs, flight controller telemetry and other devices) into a temporary folder, then
measures in the same run:

(a) python-can's ``can.LogReader`` merely iterating the file (no decoding at all);
(b) ``gimbal-analyzer decode --summary`` decoding it fully, in a separate process
    (start-up included), and that process's peak memory, also for a file a tenth the
    size, to show that memory does not grow with the file.

Prints frames per second of both and the ratio (target: (b) at least 3x (a)).
"""

from __future__ import annotations

import argparse
import json
import os
import random
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from analyzer.protocol.codec import encode_command  # noqa: E402
from analyzer.protocol.feedback import encode_attitude, encode_ranging, segments  # noqa: E402
from analyzer.protocol.uav import (  # noqa: E402
    encode_altitude,
    encode_gps,
    encode_text,
    encode_uav_attitude,
)

START = 1715680800.0
PERIOD_S = 0.01  # the schedule below repeats every 10 ms
ESC_IDS = [f"{0x0CF00400 + n:08X}" for n in range(4)]  # 4 ESCs at 400 Hz
FC_IDS = [f"{0x18FF1000 + n:08X}" for n in range(8)]  # flight controller telemetry at 100 Hz
OTHER_IDS = ["0CFE6CEE", "18FEF100", "1CEBFF00", "7E8", "100", "321"]  # slower devices


def traffic_lines(frames: int, seed: int = 1) -> Iterator[list[str]]:
    """``frames`` candump -L lines of the mix described in the module docstring, in batches."""
    rng = random.Random(seed)
    pans = [
        encode_command("gimbal_control", pan_speed_dps=p / 4, tilt_speed_dps=-p / 8).hex().upper()
        for p in range(-40, 41)
    ]
    others = [
        encode_command("specified_angle", yaw_deg=45).hex().upper(),
        encode_command("zoom", action="zoom_in").hex().upper(),
        encode_command("snapshot", mode="single").hex().upper(),
        encode_command("palette", palette="iron_red").hex().upper(),
    ]
    text = [(f"{cid:08X}", d.hex().upper()) for cid, d in encode_text("BATTERY 40 %, RTH")]
    out: list[str] = []
    append = out.append
    tick = 0
    left = frames
    while left > 0:
        t = START + tick * PERIOD_S
        stamp = f"({t:.6f}) can0 "
        for _k in range(4):  # ESCs: 4 x 400 Hz
            for esc in ESC_IDS:
                append(f"{stamp}{esc}#{rng.getrandbits(64):016X}")
        for fc in FC_IDS:  # flight controller: 8 x 100 Hz
            append(f"{stamp}{fc}#{rng.getrandbits(64):016X}")
        if tick % 10 == 0:
            for other in OTHER_IDS:
                append(f"{stamp}{other}#{rng.getrandbits(32):08X}")
        if tick % 2 == 0:  # UAV attitude at 50 Hz
            att = encode_uav_attitude(rng.uniform(-5, 5), rng.uniform(-5, 5), tick % 360 - 180)
            append(f"{stamp}0000FF13#{att.hex().upper()}")
        if tick % 10 == 5:  # GPS and altitude at 10 Hz
            gps = encode_gps(31.12 + tick * 1e-7, 118.12 + tick * 1e-7)
            append(f"{stamp}0000FF15#{gps.hex().upper()}")
            append(f"{stamp}0000FF16#{encode_altitude(100 + tick % 50).hex().upper()}")
        if tick % 5 == 0:  # gimbal control at 20 Hz
            append(f"{stamp}00000F01#{pans[tick // 5 % len(pans)]}")
        if tick % 100 == 37:
            append(f"{stamp}00000F01#{others[tick // 100 % len(others)]}")
        if tick % 50 == 25:  # gimbal feedback at 2 Hz, four segments
            if tick % 200 == 25:
                msg = encode_ranging(
                    distance_m=150, height_m=80, latitude_deg=31.1, longitude_deg=118.1
                )
            else:
                msg = encode_attitude(pitch_deg=-30, yaw_deg=tick % 360, motor_yaw_deg=0)
            for part in segments(msg):
                append(f"{stamp}030F0001#{part.hex().upper()}")
        if tick % 1000 == 500:
            for cid, data in text:
                append(f"{stamp}{cid}#{data}")
        tick += 1
        if len(out) >= 10_000 or len(out) >= left:
            batch = out[:left]
            left -= len(batch)
            yield batch
            out.clear()


PROTOCOL_ID_TEXTS = frozenset(
    {"00000F01", "030F0001", "0000FF13", "0000FF15", "0000FF16", "02008201", "02008202"}
)


def write_log(path: Path, frames: int) -> dict[str, int]:
    """Write the log batch by batch (memory stays small); count the protocol frames."""
    written = protocol = 0
    with path.open("w") as f:
        for batch in traffic_lines(frames):
            f.write("\n".join(batch) + "\n")
            written += len(batch)
            protocol += sum(1 for line in batch if line[25:33] in PROTOCOL_ID_TEXTS)
    return {"frames": written, "protocol": protocol, "bytes": path.stat().st_size}


def python_can_rate(path: Path) -> tuple[int, float]:
    import can

    started = time.perf_counter()
    count = 0
    for _msg in can.LogReader(str(path)):
        count += 1
    return count, time.perf_counter() - started


# Runs the command in a fresh process and reports that process's own peak memory
# (VmHWM counts only after exec; ru_maxrss would include the parent's pages at fork).
CHILD = """
import sys
from analyzer.cli import main
code = main(["decode", "--summary", "--json", sys.argv[1]])
sys.stdout.flush()
peak = [l for l in open("/proc/self/status") if l.startswith("VmHWM:")]
if not peak:
    import resource
    peak = ["VmHWM: %d kB" % resource.getrusage(resource.RUSAGE_SELF).ru_maxrss]
print(peak[0].strip(), file=sys.stderr)
sys.exit(code)
"""


def decode_summary(path: Path) -> tuple[dict[str, Any], float, int]:
    """Run the real command; returns its JSON summary, wall seconds and peak RSS in KiB."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    started = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-c", CHILD, str(path)], capture_output=True, env=env, check=False
    )
    seconds = time.perf_counter() - started
    if proc.returncode != 0:
        raise SystemExit(f"decode failed: {proc.stderr.decode(errors='replace')}")
    peak_kib = int(proc.stderr.decode().split()[-2])
    return json.loads(proc.stdout), seconds, peak_kib


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=1_000_000)
    parser.add_argument("--keep", metavar="DIR", help="write the logs here and keep them")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(args.keep or scratch)
        folder.mkdir(parents=True, exist_ok=True)
        big, small = folder / "bench-full.log", folder / "bench-tenth.log"
        print(f"writing {args.frames:,} frames ...", flush=True)
        info = write_log(big, args.frames)
        write_log(small, args.frames // 10)
        share = info["protocol"] / info["frames"] * 100
        print(
            f"  {info['bytes'] / 1e6:.1f} MB, {info['protocol']:,} gimbal-protocol frames "
            f"({share:.1f} %), the rest other devices"
        )

        count, seconds = python_can_rate(big)
        can_rate = count / seconds
        print(f"(a) python-can LogReader, iterating only: {count:,} frames in {seconds:.2f} s")

        summary, ours_s, rss = decode_summary(big)
        frames = int(summary["input"]["frames"])
        ours_rate = frames / ours_s
        print(
            f"(b) gimbal-analyzer decode --summary, full decode: {frames:,} frames in "
            f"{ours_s:.2f} s ({summary['events']:,} events, "
            f"{sum(summary['diagnostics'].values())} diagnostics)"
        )
        _small_summary, _small_s, small_rss = decode_summary(small)

    print()
    print(f"python-can LogReader      {can_rate:>12,.0f} frames/s")
    print(f"gimbal-analyzer decode    {ours_rate:>12,.0f} frames/s   (start-up included)")
    print(f"ratio                     {ours_rate / can_rate:>12.1f} x   (target >= 3 x)")
    print(
        f"peak memory of (b)        {rss / 1024:>9.1f} MiB for {args.frames:,} frames, "
        f"{small_rss / 1024:.1f} MiB for {args.frames // 10:,}"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
