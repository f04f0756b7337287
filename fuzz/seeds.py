"""Seed files: the samples, and each format written from their frames as its tool writes it."""

from __future__ import annotations

import gzip
from dataclasses import dataclass
from pathlib import Path

from analyzer.protocol.types import CanFrame
from tests.log_makers import (
    SAMPLE,
    ardupilot_log,
    flight_frames,
    python_can_log,
    savvycan_csv,
    sll_pcap,
)
from tests.rosbag2_files import ros1_bag, rosbag2_mcap
from tests.test_mcap_support import traffic, write_recording
from tests.test_ros_bags import rosbags_bag

SAMPLES = SAMPLE.parent
FRAMES = 40  # frames per seed file: small files keep each read in milliseconds


@dataclass(frozen=True)
class Seed:
    """A file as its tool writes it: ``name`` (the suffix matters), ``fmt`` its format."""

    name: str
    fmt: str
    data: bytes


def seed_frames() -> list[CanFrame]:
    """The first frames of the flight sample (commands, feedback, UAV status, text)."""
    return flight_frames()[:FRAMES]


def python_can_bytes(folder: Path, name: str, frames: list[CanFrame]) -> bytes:
    """``frames`` written by python-can's writer of ``name``'s suffix."""
    return python_can_log(folder / name, frames).read_bytes()


def candump_screen(frames: list[CanFrame]) -> bytes:
    """candump's default screen output with -ta: ``(time)  can0  ID   [n]  AA BB ...``."""
    lines = []
    for frame in frames:
        ident = f"{frame.can_id:08X}" if frame.extended else f"{frame.can_id:03X}"
        data = " ".join(f"{b:02X}" for b in frame.data)
        lines.append(f" ({frame.time:.6f})  can0  {ident}   [{len(frame.data)}]  {data}")
    return ("\n".join(lines) + "\n").encode()


def make_seeds(folder: Path, *, recording_s: float = 1.0) -> list[Seed]:
    """One or more files of every input format, written into ``folder`` on the way;
    ``recording_s``: the seconds of traffic in this tool's own recording."""
    frames = seed_frames()
    log = b"".join(SAMPLE.read_bytes().splitlines(keepends=True)[:FRAMES])
    dataflash, _ = ardupilot_log(frames, frames[0].time - 30.0)
    seeds = [
        Seed("flight.log", "candump", log),
        Seed("screen.log", "candump", candump_screen(frames)),
        Seed("flight.log.gz", "candump", gzip.compress(log)),
        Seed("idu-tcp.pcap", "pcap", (SAMPLES / "idu-tcp.pcap").read_bytes()),
        Seed("sll.pcap", "pcap", sll_pcap(folder / "sll.pcap", frames, 113).read_bytes()),
        Seed(
            "sll2.pcapng", "pcap", sll_pcap(folder / "s.pcapng", frames, 276, ng=True).read_bytes()
        ),
        Seed("uart-dump.bin", "stream", (SAMPLES / "uart-dump.bin").read_bytes()),
        Seed("00000042.BIN", "dataflash", dataflash),
        Seed("00000043.BIN.gz", "dataflash", gzip.compress(dataflash)),
        Seed("gvret.csv", "savvycan", savvycan_csv(frames).encode()),
        Seed("rosbag2.mcap", "mcap", rosbag2_mcap(frames)),
        Seed("ros1.bag", "rosbag", ros1_bag(folder / "r.bag", frames).read_bytes()),
        Seed("bag.db3", "rosbag", rosbags_bag(folder / "bag", frames, "db3").read_bytes()),
    ]
    for name in ("x.asc", "x.blf", "x.trc", "x.csv", "x.mf4", "x.asc.gz", "x.trc.gz"):
        fmt = name.split(".")[1]
        seeds.append(Seed(name, fmt, python_can_bytes(folder, name, frames)))
    write_recording(folder / "rec.mcap", traffic(recording_s))
    seeds.append(Seed("recording.mcap", "mcap", (folder / "rec.mcap").read_bytes()))
    # Uncompressed (record --compression none): a mutation lands in a record, not in zstd.
    write_recording(folder / "plain.mcap", traffic(recording_s), compression="none")
    seeds.append(Seed("plain-recording.mcap", "mcap", (folder / "plain.mcap").read_bytes()))
    return seeds
