"""Targets that read a file of each input format: ``read``, ``analyze`` and ``decode``.

Each input is written to a file with the format's name and read three ways, as users
do: ``analyzer.read(path, format)`` (only ValueError / FileNotFoundError may escape),
``analyzer.analyze`` of the events it gave, and ``gimbal-analyzer decode PATH --format``
(exit 0, or exit 2 with one ``error:`` line). The reader comes from
``analyzer.read``, whichever module implements the format: the targets stay the same
when a reader is replaced.
"""

from __future__ import annotations

import atexit
import functools
import os
import shutil
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from fuzz.rules import cli, library
from fuzz.seeds import Seed, make_seeds

# The seconds of traffic in the seed recording of the mcap target (a small file keeps
# each execution short; the recording's layout is the same at any length).
RECORDING_S = 0.25


@dataclass(frozen=True)
class FileFormat:
    """A target's file: its name (the suffix a user's file has), its ``--format`` and
    which seed files start its corpus."""

    target: str
    name: str
    fmt: str
    seeds: Callable[[Seed], bool]
    what: str


def _named(*suffixes: str) -> Callable[[Seed], bool]:
    return lambda seed: seed.name.endswith(suffixes)


def _of(fmt: str) -> Callable[[Seed], bool]:
    return lambda seed: seed.fmt == fmt


FILE_FORMATS: tuple[FileFormat, ...] = (
    FileFormat("candump", "fuzz.log", "candump", _of("candump"), "candump -L logs and screen"),
    FileFormat("asc", "fuzz.asc", "asc", _of("asc"), "Vector ASC (python-can)"),
    FileFormat("trc", "fuzz.trc", "trc", _of("trc"), "PCAN-View TRC (python-can)"),
    FileFormat("csv", "fuzz.csv", "csv", _of("csv"), "python-can CSV"),
    FileFormat("blf", "fuzz.blf", "blf", _of("blf"), "Vector BLF"),
    FileFormat("mf4", "fuzz.mf4", "mf4", _of("mf4"), "ASAM MDF4 (python-can, asammdf)"),
    FileFormat("pcap", "fuzz.pcap", "pcap", _named(".pcap"), "pcap of TCP and of SocketCAN"),
    FileFormat("pcapng", "fuzz.pcapng", "pcap", _named(".pcapng"), "pcapng of SocketCAN"),
    FileFormat("stream", "fuzz.bin", "stream", _of("stream"), "raw TCP / UART byte dumps"),
    FileFormat("dataflash", "fuzz.BIN", "dataflash", _of("dataflash"), "ArduPilot DataFlash"),
    FileFormat("savvycan", "fuzz.csv", "savvycan", _of("savvycan"), "SavvyCAN / GVRET CSV"),
    FileFormat("ros1", "fuzz.bag", "rosbag", _named(".bag"), "ROS 1 bags"),
    FileFormat("ros2-db3", "fuzz.db3", "rosbag", _named(".db3"), "ROS 2 bags, sqlite3"),
    FileFormat("ros2-mcap", "fuzz.mcap", "mcap", _named("rosbag2.mcap"), "ROS 2 bags, MCAP"),
    FileFormat("mcap", "fuzz.mcap", "mcap", _named("recording.mcap"), "this tool's recordings"),
)


@functools.cache
def scratch() -> Path:
    """A folder for this process's input files (in memory where the system has one)."""
    shm = "/dev/shm"
    folder = tempfile.mkdtemp(prefix="gimbal-fuzz-", dir=shm if os.path.isdir(shm) else None)
    atexit.register(shutil.rmtree, folder, True)
    return Path(folder)


@functools.cache
def all_seeds() -> tuple[Seed, ...]:
    """The seed files of every format (made once per process)."""
    folder = scratch() / "seeds"
    folder.mkdir(exist_ok=True)
    return tuple(make_seeds(folder, recording_s=RECORDING_S))


def read_file(fmt: str, path: Path) -> None:
    """``path`` read by the library, its events analysed, and decoded by the command."""
    from analyzer.api.analysis import analyze
    from analyzer.api.reading import read

    events = library(lambda: list(read(path, fmt)))
    if events is not None:
        library(lambda: list(analyze(events)))
    cli(["decode", str(path), "--format", fmt])


def file_runner(spec: FileFormat) -> Callable[[bytes], None]:
    def run(data: bytes) -> None:
        path = scratch() / spec.name
        path.write_bytes(data)
        read_file(spec.fmt, path)

    return run


def file_seeds(spec: FileFormat) -> Callable[[], list[bytes]]:
    def seeds() -> list[bytes]:
        return [seed.data for seed in all_seeds() if spec.seeds(seed)]

    return seeds
