"""Simulated flights with the simulated camera's video (offline), and what their lens really did."""

from __future__ import annotations

import bisect
import json
from pathlib import Path
from typing import Any

from analyzer.sim.behaviour import Behaviour
from analyzer.sim.engine import SimConfig, SimulatedGimbal
from analyzer.sim.ground import Step
from analyzer.sim.offline import run_offline
from tests.fleet_flights import cli_output

START = 1_700_000_000.0  # the offline recordings' first second


def record(
    path: Path,
    steps: tuple[Step, ...],
    duration: float,
    *,
    ignore: frozenset[str] = frozenset(),
    streams: tuple[str, ...] = ("main",),
    gaps: tuple[tuple[float, float], ...] = (),
    uav: bool = True,
    gimbal_type: int = 1,
) -> Path:
    """A recording as `demo --video` makes it, in virtual time (the simulated gimbal, UAV,
    ground station and camera), written to ``path``."""
    from analyzer.sim.camera.offline import record_offline

    config = SimConfig(
        gimbal_type=gimbal_type, uav=uav, behaviour=Behaviour(ignore=ignore), ranging=False
    )
    record_offline(path, steps, duration, config, streams=streams, start=START, gaps=gaps)
    return path


class Lens:
    """The simulated lens's magnification (optical times digital zoom) over time, as the
    model had it at every tick of the same flight played again."""

    def __init__(self, steps: tuple[Step, ...], duration: float, *, uav: bool = True) -> None:
        self.times: list[float] = []
        self.zooms: list[float] = []

        def watch(now: float, gimbal: SimulatedGimbal) -> None:
            self.times.append(now)
            self.zooms.append(gimbal.model.zoom * gimbal.model.digital_zoom)

        run_offline(steps, duration, SimConfig(uav=uav), start=START, watch=watch)

    def at(self, t: float) -> float:
        index = min(len(self.times) - 1, bisect.bisect_left(self.times, t - 1e-6))
        return self.zooms[index]


def camera_findings(path: Path, *extra: str) -> list[dict[str, Any]]:
    """The camera findings `analyze --json` makes of a recording, in time order."""
    lines = cli_output("analyze", str(path), "--json", "-q", *extra).splitlines()
    found = [json.loads(line) for line in lines]
    return [f for f in found if f.get("check") == "picture"]
