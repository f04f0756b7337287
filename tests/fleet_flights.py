"""A small fleet of simulated flights with known faults, and the helpers the fleet tests share.

Each flight is a session of the simulated gimbal in virtual time, written as the capture
tools write it: a candump -L log, or an MCAP recording made from one by `convert`.
"""

from __future__ import annotations

import contextlib
import io
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from analyzer.cli import main
from analyzer.protocol.types import CanFrame
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.engine import SimConfig
from analyzer.sim.faults import FaultConfig
from analyzer.sim.ground import Step
from analyzer.sim.offline import run_offline

START = 1_700_000_000.0  # 2023-11-14, a Tuesday (ISO week 46)
WEEK = 7 * 86400.0
SCRIPT = (
    Step(1.0, "specified_angle", {"yaw_deg": 45}),
    Step(7.0, "gimbal_control", {"tilt_speed_dps": -10}, until=9.0),
    Step(13.0, "tracking", {"x": 4096, "y": 4096, "width": 320, "height": 240}),
    Step(19.0, "look_down"),
)
SECONDS = 26.0


@dataclass(frozen=True)
class Flight:
    folder: str  # the gimbal it flew with: A or B
    name: str
    start: float
    config: SimConfig
    mcap: bool = False


FLIGHTS = (
    Flight("A", "a-clean.log", START, SimConfig()),
    Flight("A", "a-clean-next-week.log", START + WEEK, SimConfig(), mcap=True),
    # CRC errors: corrupted feedback segments.
    Flight("B", "b-crc.log", START, SimConfig(faults=FaultConfig(corrupt=0.08, seed=11))),
    # A gimbal that ignores tracking and whose feedback stops for 3 s: one gap.
    Flight(
        "B",
        "b-deaf.log",
        START + WEEK,
        SimConfig(
            behaviour=Behaviour(ignore=frozenset({"tracking"})),
            faults=FaultConfig(stop_at=3.0, stop_for=3.0),
        ),
    ),
)
DAMAGED = "b-damaged.mcap"  # an MCAP magic and then noise: read, with a diagnostic
UNREADABLE = "b-cut.pcap"  # a pcap file cut off inside its header: no capture at all


def candump(path: Path, frames: list[CanFrame]) -> Path:
    lines = [f"({f.time:.6f}) can0 {f.can_id:08X}#{f.data.hex().upper()}" for f in frames]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def make_fleet(root: Path) -> dict[str, Path]:
    """flights/A and flights/B with the flights above; name -> path."""
    made: dict[str, Path] = {}
    for flight in FLIGHTS:
        folder = root / "flights" / flight.folder
        folder.mkdir(parents=True, exist_ok=True)
        frames, _ = run_offline(SCRIPT, SECONDS, flight.config, start=flight.start)
        if not flight.mcap:
            made[flight.name] = candump(folder / flight.name, frames)
            continue
        work = root / "work"
        work.mkdir(exist_ok=True)
        log = candump(work / flight.name, frames)
        recording = folder / (Path(flight.name).stem + ".mcap")
        assert main(["convert", str(log), "-o", str(recording), "-q"]) == 0
        made[recording.name] = recording
    damaged = root / "flights" / "B" / DAMAGED
    damaged.write_bytes(b"\x89MCAP0\r\n" + bytes(range(256)) * 4)
    made[DAMAGED] = damaged
    cut = root / "flights" / "B" / UNREADABLE
    cut.write_bytes(b"\xd4\xc3\xb2\xa1\x02\x00")
    made[UNREADABLE] = cut
    return made


TAGS = {
    "A": ("--tag", "gimbal=A", "--tag", "firmware=1.2"),
    "B": ("--tag", "gimbal=B", "--tag", "firmware=1.3"),
}


def cli(*args: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(args))
    return code, out.getvalue(), err.getvalue()


def cli_output(*args: str) -> str:
    """What a command that must succeed prints on standard output."""
    code, out, err = cli(*args)
    assert code == 0, err
    return out


def built_fleet(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """The fleet above in two `table` runs (A with one worker, B with two), for a fixture."""
    root = tmp_path_factory.mktemp("fleet")
    files = make_fleet(root)
    dataset = root / "dataset"
    runs = {}
    for folder, workers in (("A", "1"), ("B", "2")):
        code, out, err = cli(
            "table", str(root / "flights" / folder), "-o", str(dataset), *TAGS[folder],
            "--workers", workers,
        )  # fmt: skip
        assert code == 0, err
        runs[folder] = out
    return {"root": root, "files": files, "dataset": dataset, "runs": runs}


def rows(dataset: Path, table: str) -> list[dict[str, Any]]:
    """Every row of a table, read with pyarrow as a user would."""
    files = sorted((dataset / table).glob("*.parquet"))
    if not files:
        return []
    return pa.concat_tables(
        [pq.read_table(f) for f in files], promote_options="default"
    ).to_pylist()


def recording(dataset: Path, name: str) -> dict[str, Any]:
    (row,) = [r for r in rows(dataset, "recordings") if r["recording"] == name]
    return row


def questions(dataset: Path) -> dict[str, list[dict[str, Any]]]:
    code, out, err = cli("fleet", str(dataset), "--json")
    assert code == 0, err
    found: dict[str, list[dict[str, Any]]] = {}
    for line in out.splitlines():
        obj = json.loads(line)
        found.setdefault(obj.pop("question"), []).append(obj)
    return found
