"""DataFlash reading speed (records/s) against pymavlink's DFReader, in the same run.

Writes an ArduPilot log as a flight with CAN logging leaves it: FMT records first, then
IMU at 400 Hz, ATT at 100 Hz, GPS at 5 Hz and every frame of a busy CAN bus as CANF
(gimbal and UAV traffic of convert_speed.py, padded with other devices; data changes
from frame to frame). Times how long our reader takes to give every CAN frame, and how
long DFReader takes to give every CANF record (its index pass included, as a user of
it pays it). Each side runs several times, interleaved; the best time of each counts.

  python benchmarks/dataflash_speed.py [--frames 200000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.convert_speed import make_frames
from tests.log_makers import (
    CANF,
    EFF,
    GPS,
    DataFlashWriter,
    gps_record,
    start_log,
)

IMU, ATT = 75, 76


def write_log(path: Path, frame_count: int) -> int:
    """The log; returns its number of records."""
    frames = make_frames(frame_count)
    writer = DataFlashWriter()
    start_log(writer, [GPS, CANF])
    imu = "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,EG,EA,T,GH,AH,GHz,AHz"
    writer.fmt(IMU, "IMU", "QBffffffIIfBBHH", imu)
    att = "TimeUS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw,ErrRP,ErrYaw,AEKF"
    writer.fmt(ATT, "ATT", "QccccCCCCB", att)
    boot = frames[0].time - 60.0
    records = 0
    next_imu = next_att = next_gps = 0
    for n, frame in enumerate(frames):
        us = round((frame.time - boot) * 1e6)
        while next_imu * 2500 <= us:
            t = next_imu * 2500
            wobble = (next_imu % 97) / 97.0
            writer.record(
                IMU,
                t,
                0,
                wobble / 10,
                0.01,
                -0.02,
                wobble,
                -wobble,
                -9.81,
                0,
                0,
                35.0,
                1,
                1,
                2000,
                1000,
            )
            next_imu += 1
            records += 1
        while next_att * 10000 <= us:
            a = next_att % 3600
            writer.record(
                ATT, next_att * 10000, a, a + 1, -a, -a - 1, a * 10 % 36000, a * 10 % 36000, 1, 1, 3
            )
            next_att += 1
            records += 1
        while next_gps * 200_000 <= us:
            ms = 208_818_000 + next_gps * 200
            gps_record(writer, next_gps * 200_000, 3, 2314, ms, 473977420 + next_gps)
            next_gps += 1
            records += 1
        ident = frame.can_id | (EFF if frame.extended else 0)
        writer.record(CANF, us, n % 2, ident, len(frame.data), *frame.data.ljust(8, b"\0"))
        records += 1
    path.write_bytes(bytes(writer.out))
    return records


def ours(path: Path) -> int:
    from analyzer.inputs.dataflash.reader import DataFlashReader
    from analyzer.protocol.types import CanFrame

    with DataFlashReader(str(path)) as reader:
        return sum(1 for item in reader if isinstance(item, CanFrame))


def dfreader(path: Path) -> int:
    from pymavlink import DFReader

    log = DFReader.DFReader_binary(str(path))
    count = 0
    while log.recv_match(type="CANF") is not None:
        count += 1
    return count


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=200_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "00000001.BIN"
        records = write_log(path, args.frames)
        size = os.path.getsize(path)
        print(f"log: {records:,} records ({args.frames:,} CANF), {size / 1e6:.1f} MB")
        best = {"ours": float("inf"), "DFReader": float("inf")}
        for _ in range(args.repeat):
            for name, run in (("ours", ours), ("DFReader", dfreader)):
                start = time.perf_counter()
                got = run(path)
                best[name] = min(best[name], time.perf_counter() - start)
                assert got == args.frames, (name, got)
        for name, seconds in best.items():
            print(
                f"{name:>9}: {seconds:6.2f} s  {records / seconds:>12,.0f} records/s  "
                f"{args.frames / seconds:>10,.0f} CAN frames/s"
            )
        print(f"ratio: ours is {best['DFReader'] / best['ours']:.1f} x as fast as DFReader")
    return 0


if __name__ == "__main__":
    sys.exit(main())
