"""Decode speed: ``gimbal-analyzer decode --summary`` against python-can's LogReader, same file.

    python benchmarks/decode_speed.py [--mix busy|dense|random-ids|dense-repeat|all] [--frames N]
                                      [--keep DIR] [--repeat N]

Writes a candump -L log of one of these kinds of bus into a temporary folder:

busy        a busy drone bus: ESCs, flight controller telemetry and other devices, 3.9 %
            gimbal protocol (feedback, control commands, UAV status);
dense       a protocol-dense bus (gimbal bench, or gimbal and flight controller as most of
            the traffic): per 50 frames 4 feedback segments, 9 gimbal_control commands,
            5 GPS frames and 32 frames of 80 foreign IDs (36 % protocol);
random-ids  the dense schedule, but every foreign frame has a new ID (address-claiming
            devices, or a damaged log);
dense-repeat  the dense schedule with the values of earlier versions of this benchmark:
            81 distinct ``gimbal_control`` frames and 52 feedback messages, cycled. It
            shows what remembering decoded bytes gives; the goals are not measured on it.

Every value changes as on a real bus: the gimbal's attitude moves in every feedback
message (a random walk of pitch, yaw and motor yaw), the ``gimbal_control`` commands are
a pilot's stick (movements of 1 to 4 s that rise smoothly to a random peak in +-60 deg/s
and fall back, an analog stick's jitter of a few 0.01 deg/s, then 0.5 to 3 s centred
with zeros sent: the speeds change in every command), GPS positions move, UAV attitude
varies.

and measures in the same run, as CPU time:

(a) python-can's ``can.LogReader`` merely iterating the file (no decoding at all);
(b) ``gimbal-analyzer decode --summary`` decoding it fully, in a separate process
    (start-up included), and that process's peak memory, also for a file a tenth the
    size, to show that memory does not grow with the file.

Prints frames per second of both and the ratio. Targets: busy >= 4.7x, dense >= 3x,
random-ids >= 1.5x. ``--mix all`` (the default) runs those three one after the other.

Each side is measured ``--repeat`` times (default 3), the two alternating, and the
fastest run of each counts: on a shared machine a run is only ever slowed down by other
work, never sped up. The package's bytecode is compiled first, as ``pip install`` does,
so that start-up does not include compiling the sources.
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
from analyzer.sim.pilot import profile  # noqa: E402

START = 1715680800.0
PERIOD_S = 0.01  # the schedule below repeats every 10 ms
ESC_IDS = [f"{0x0CF00400 + n:08X}" for n in range(4)]  # 4 ESCs at 400 Hz
FC_IDS = [f"{0x18FF1000 + n:08X}" for n in range(8)]  # flight controller telemetry at 100 Hz
OTHER_IDS = ["0CFE6CEE", "18FEF100", "1CEBFF00", "7E8", "100", "321"]  # slower devices


ZERO_SPEEDS = encode_command("gimbal_control").hex().upper()


class Pilot:
    """A pilot's stick over time: movements of 1 to 4 s to a random peak, smooth (the
    simulator's stick profile) with a reading's jitter, then 0.5 to 3 s centred (zeros)."""

    def __init__(self, rng: random.Random) -> None:
        self.rng = rng
        self.start = self.until = START
        self.centred = True
        self.peak = (0.0, 0.0)

    def command(self, t: float) -> str:
        """The ``gimbal_control`` the ground station sends at ``t``, as candump hex."""
        rng = self.rng
        if t >= self.until:
            self.centred = not self.centred
            self.start = t
            self.until = t + (rng.uniform(0.5, 3.0) if self.centred else rng.uniform(1.0, 4.0))
            self.peak = (rng.uniform(-60, 60), rng.uniform(-60, 60))
        if self.centred:
            return ZERO_SPEEDS
        shape = profile((t - self.start) / (self.until - self.start))
        pan, tilt = (round(p * shape + rng.gauss(0.0, 0.03), 2) for p in self.peak)
        return (
            encode_command("gimbal_control", pan_speed_dps=pan, tilt_speed_dps=tilt).hex().upper()
        )


class Gimbal:
    """Attitude that moves between feedback messages (a random walk), as a flying gimbal's."""

    def __init__(self, rng: random.Random) -> None:
        self.rng = rng
        self.pitch, self.yaw, self.motor = -30.0, 0.0, 0.0

    def attitude(self) -> list[str]:
        rng = self.rng
        self.pitch = max(-90.0, min(30.0, self.pitch + rng.uniform(-3, 3)))
        self.yaw = (self.yaw + rng.uniform(-5, 5)) % 360
        self.motor = max(-160.0, min(160.0, self.motor + rng.uniform(-4, 4)))
        message = encode_attitude(pitch_deg=self.pitch, yaw_deg=self.yaw, motor_yaw_deg=self.motor)
        return [part.hex().upper() for part in segments(message)]


def traffic_lines(frames: int, seed: int = 1) -> Iterator[list[str]]:
    """``frames`` candump -L lines of the mix described in the module docstring, in batches."""
    rng = random.Random(seed)
    gimbal = Gimbal(rng)
    pilot = Pilot(random.Random(seed + 2))
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
            append(f"{stamp}00000F01#{pilot.command(t)}")
        if tick % 100 == 37:
            append(f"{stamp}00000F01#{others[tick // 100 % len(others)]}")
        if tick % 50 == 25:  # gimbal feedback at 2 Hz, four segments
            if tick % 200 == 25:
                msg = encode_ranging(
                    distance_m=rng.uniform(100, 200),
                    height_m=rng.uniform(60, 90),
                    latitude_deg=31.1 + tick * 1e-7,
                    longitude_deg=118.1 + tick * 1e-7,
                )
                parts = [part.hex().upper() for part in segments(msg)]
            else:
                parts = gimbal.attitude()
            for part in parts:
                append(f"{stamp}030F0001#{part}")
        if tick % 1000 == 500:
            for cid, data in text:
                append(f"{stamp}{cid}#{data}")
        tick += 1
        if len(out) >= 10_000 or len(out) >= left:
            batch = out[:left]
            left -= len(batch)
            yield batch
            out.clear()


def dense_lines(
    frames: int, *, random_ids: bool = False, repeat: bool = False, seed: int = 1
) -> Iterator[list[str]]:
    """The dense (or random-ids, or dense-repeat) mix: 50-frame blocks, one every 25 ms."""
    rng = random.Random(seed)
    gimbal = Gimbal(random.Random(seed + 1))
    pilot = Pilot(random.Random(seed + 2))
    pans = [
        encode_command("gimbal_control", pan_speed_dps=p / 4, tilt_speed_dps=-p / 8).hex().upper()
        for p in range(-40, 41)
    ]
    foreign = [f"{0x18F00000 + n * 0x101:08X}" for n in range(80)]
    feedback = [
        [
            p.hex().upper()
            for p in segments(encode_attitude(pitch_deg=-30, yaw_deg=y, motor_yaw_deg=0))
        ]
        for y in range(0, 360, 7)
    ]
    # In each block: which slots carry which protocol frame (the rest are foreign).
    slots = ["F"] * 4 + ["C"] * 9 + ["G"] * 5 + ["X"] * 32
    order = slots[:]
    rng.shuffle(order)
    order = [s for s in order if s != "F"]
    order[10:10] = ["F"] * 4  # the four segments of a feedback message follow each other
    out: list[str] = []
    append = out.append
    block = 0
    left = frames
    while left > 0:
        t0 = START + block * 0.025
        segs = feedback[block % len(feedback)] if repeat else gimbal.attitude()
        k = 0
        for i, kind in enumerate(order):
            stamp = f"({t0 + i * 0.0005:.6f}) can0 "
            if kind == "F":
                append(f"{stamp}030F0001#{segs[k]}")
                k += 1
            elif kind == "C" and repeat:
                append(f"{stamp}00000F01#{pans[(block * 9 + i) % len(pans)]}")
            elif kind == "C":
                append(f"{stamp}00000F01#{pilot.command(t0 + i * 0.0005)}")
            elif kind == "G":
                gps = encode_gps(31.12 + block * 1e-7, 118.12 + i * 1e-7)
                append(f"{stamp}0000FF15#{gps.hex().upper()}")
            elif random_ids:
                cid = rng.getrandbits(29) | 0x04000000  # never one of the protocol's IDs
                append(f"{stamp}{cid:08X}#{rng.getrandbits(64):016X}")
            else:
                append(f"{stamp}{foreign[rng.randrange(80)]}#{rng.getrandbits(64):016X}")
        block += 1
        if len(out) >= 10_000 or len(out) >= left:
            batch = out[:left]
            left -= len(batch)
            yield batch
            out.clear()


MIXES = {
    "busy": traffic_lines,
    "dense": dense_lines,
    "random-ids": lambda frames: dense_lines(frames, random_ids=True),
    "dense-repeat": lambda frames: dense_lines(frames, repeat=True),
}
TARGETS = {"busy": 4.7, "dense": 3.0, "random-ids": 1.5}

PROTOCOL_ID_TEXTS = frozenset(
    {"00000F01", "030F0001", "0000FF13", "0000FF15", "0000FF16", "02008201", "02008202"}
)


def write_log(path: Path, frames: int, mix: str = "busy") -> dict[str, int]:
    """Write the log batch by batch (memory stays small); count the protocol frames."""
    written = protocol = 0
    with path.open("w", encoding="utf-8") as f:
        for batch in MIXES[mix](frames):
            f.write("\n".join(batch) + "\n")
            written += len(batch)
            protocol += sum(1 for line in batch if line[25:33] in PROTOCOL_ID_TEXTS)
    return {"frames": written, "protocol": protocol, "bytes": path.stat().st_size}


def python_can_rate(path: Path) -> tuple[int, float]:
    import can

    started = time.process_time()
    count = 0
    for _msg in can.LogReader(str(path)):
        count += 1
    return count, time.process_time() - started


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
    """Run the real command; returns its JSON summary, CPU seconds and peak RSS in KiB."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    before = os.times()
    proc = subprocess.run(
        [sys.executable, "-c", CHILD, str(path)], capture_output=True, env=env, check=False
    )
    after = os.times()
    seconds = (after.children_user - before.children_user) + (
        after.children_system - before.children_system
    )
    if proc.returncode != 0:
        raise SystemExit(f"decode failed: {proc.stderr.decode(errors='replace')}")
    peak_kib = int(proc.stderr.decode().split()[-2])
    return json.loads(proc.stdout), seconds, peak_kib


def measure(mix: str, frames_wanted: int, folder: Path, repeat: int) -> dict[str, Any]:
    big, small = folder / f"bench-{mix}-full.log", folder / f"bench-{mix}-tenth.log"
    print(f"[{mix}] writing {frames_wanted:,} frames ...", flush=True)
    info = write_log(big, frames_wanted, mix)
    write_log(small, frames_wanted // 10, mix)
    share = info["protocol"] / info["frames"] * 100
    print(
        f"  {info['bytes'] / 1e6:.1f} MB, {info['protocol']:,} gimbal-protocol frames "
        f"({share:.1f} %), the rest other devices"
    )
    theirs: list[float] = []
    ours: list[float] = []
    for _ in range(repeat):  # alternating, so that a slow spell of the machine hits both
        count, seconds = python_can_rate(big)
        theirs.append(seconds)
        summary, ours_s, rss = decode_summary(big)
        ours.append(ours_s)
    seconds, ours_s = min(theirs), min(ours)
    can_rate = count / seconds
    print(
        f"  (a) python-can LogReader, iterating only: {count:,} frames in {seconds:.2f} s CPU "
        f"(best of {_runs(theirs)})"
    )
    frames = int(summary["input"]["frames"])
    ours_rate = frames / ours_s
    print(
        f"  (b) gimbal-analyzer decode --summary, full decode: {frames:,} frames in "
        f"{ours_s:.2f} s CPU (best of {_runs(ours)}; {summary['events']:,} events, "
        f"{summary['diagnostics']} diagnostics)"
    )
    _small_summary, _small_s, small_rss = decode_summary(small)
    return {
        "mix": mix,
        "share": share,
        "can_rate": can_rate,
        "ours_rate": ours_rate,
        "ratio": ours_rate / can_rate,
        "rss": rss,
        "small_rss": small_rss,
        "frames": frames_wanted,
    }


def _runs(seconds: list[float]) -> str:
    return ", ".join(f"{s:.2f}" for s in seconds)


def compile_package() -> None:
    """Write the package's bytecode, as an installed package has it."""
    import compileall

    compileall.compile_dir(str(ROOT / "analyzer"), quiet=1)


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--mix", choices=[*MIXES, "all"], default="all")
    parser.add_argument("--frames", type=int, default=1_000_000)
    parser.add_argument("--keep", metavar="DIR", help="write the logs here and keep them")
    parser.add_argument(
        "--repeat", type=int, default=3, help="runs of each side; the fastest counts"
    )
    args = parser.parse_args()
    if args.repeat < 1:
        parser.error("--repeat must be at least 1")
    compile_package()
    mixes = list(TARGETS) if args.mix == "all" else [args.mix]
    results = []
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(args.keep or scratch)
        folder.mkdir(parents=True, exist_ok=True)
        for mix in mixes:
            results.append(measure(mix, args.frames, folder, args.repeat))
            for name in (f"bench-{mix}-full.log", f"bench-{mix}-tenth.log"):
                if not args.keep:
                    (folder / name).unlink()
    print()
    print(
        f"{'mix':<11} {'protocol':>8}  {'python-can':>12}  {'decode':>12}  {'ratio':>6}  "
        f"{'target':>6}  peak memory (full / tenth)"
    )
    for r in results:
        target = TARGETS.get(r["mix"])
        met = "-" if target is None else "met" if r["ratio"] >= target else "NOT met"
        goal = "-" if target is None else f"{target:.1f}x"
        print(
            f"{r['mix']:<11} {r['share']:>7.1f}%  {r['can_rate']:>10,.0f}/s  "
            f"{r['ours_rate']:>10,.0f}/s  {r['ratio']:>5.2f}x  {goal:>6}  "
            f"{r['rss'] / 1024:.1f} / {r['small_rss'] / 1024:.1f} MiB   {met}"
        )
    print("frames/s over CPU time; decode includes start-up; python-can iterates only")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
