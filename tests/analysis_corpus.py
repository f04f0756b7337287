"""Inputs the response analysis is checked on: every sample, the fault logs, the fleet's
flights, simulator sessions with every kind of disobedience and fault, and a slice of the
dense bus mix of the benchmarks. Each is written the way the capture tools write it (a
candump -L log), the same bytes every time.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

from analyzer.protocol.types import CanFrame
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.engine import SimConfig
from analyzer.sim.faults import FaultConfig
from analyzer.sim.ground import DEMO_SCRIPT, pilot_script
from analyzer.sim.offline import run_offline
from tests.fault_logs import CANDUMP_NAME, STREAM_NAME, write_fault_logs
from tests.fleet_flights import FLIGHTS
from tests.fleet_flights import SCRIPT as FLEET_SCRIPT
from tests.fleet_flights import SECONDS as FLEET_SECONDS
from tests.log_makers import ardupilot_log, flight_frames, savvycan_csv, sll_pcap

ROOT = Path(__file__).resolve().parents[1]
SAMPLES = ROOT / "samples"
START = 1_715_680_800.0
DENSE_FRAMES = 20_000

# name -> the simulator's configuration for a session of the demo's script (14 s).
SESSIONS: dict[str, SimConfig] = {
    "sim-clean.log": SimConfig(ranging=True, uav=True),
    "sim-demo-faults.log": SimConfig(
        ranging=True,
        uav=True,
        faults=FaultConfig(drop=0.02, corrupt=0.02, duplicate=0.02, delay=0.02, seed=7),
    ),
    "sim-drop.log": SimConfig(ranging=True, uav=True, faults=FaultConfig(drop=0.1, seed=3)),
    "sim-ignore-tracking.log": SimConfig(
        ranging=True, uav=True, behaviour=Behaviour(ignore=frozenset({"tracking"}))
    ),
    "sim-ignore-stop.log": SimConfig(
        ranging=True, uav=True, behaviour=Behaviour(ignore=frozenset({"tracking_stop"}))
    ),
    "sim-disobedient.log": SimConfig(
        ranging=True,
        uav=True,
        heading_deg=30.0,
        behaviour=Behaviour(speed=0.4, reach=0.7, drift_s=1.0, geodetic_as_airframe=True),
    ),
    "sim-outage.log": SimConfig(ranging=True, faults=FaultConfig(stop_at=5.0, stop_for=3.0)),
}
SESSION_SECONDS = 14.0
# The demo's script with its gimbal_control played on a pilot's stick (speeds changing in
# every command), against a gimbal that follows and one that turns at 0.4 of the speed.
STICK_SESSIONS: dict[str, SimConfig] = {
    "sim-stick.log": SimConfig(ranging=True, uav=True),
    "sim-stick-sluggish.log": SimConfig(ranging=True, uav=True, behaviour=Behaviour(speed=0.4)),
}


def candump_text(frames: list[CanFrame]) -> str:
    lines = [f"({f.time:.6f}) can0 {f.can_id:08X}#{f.data.hex().upper()}" for f in frames]
    return "\n".join(lines) + "\n"


def _decode_speed() -> ModuleType:
    """benchmarks/decode_speed.py (its dense mix generator), imported from its path."""
    name = "decode_speed_benchmark"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / "decode_speed.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def write_corpus(folder: Path) -> dict[str, Path]:
    """Every input of the corpus: name -> path (samples in place, the rest written to folder)."""
    made = {p.name: p for p in sorted(SAMPLES.iterdir()) if p.name != "README.md"}
    write_fault_logs(folder)
    made[CANDUMP_NAME] = folder / CANDUMP_NAME
    made[STREAM_NAME] = folder / STREAM_NAME
    for flight in FLIGHTS:
        frames, _ = run_offline(FLEET_SCRIPT, FLEET_SECONDS, flight.config, start=flight.start)
        path = folder / f"fleet-{flight.name}"
        path.write_text(candump_text(frames), encoding="utf-8")
        made[path.name] = path
    for name, config in SESSIONS.items():
        frames, _ = run_offline(DEMO_SCRIPT, SESSION_SECONDS, config, start=START)
        path = folder / name
        path.write_text(candump_text(frames), encoding="utf-8")
        made[name] = path
    for name, config in STICK_SESSIONS.items():
        frames, _ = run_offline(pilot_script(), SESSION_SECONDS, config, start=START)
        path = folder / name
        path.write_text(candump_text(frames), encoding="utf-8")
        made[name] = path
    # The sample's frames as other tools write them (ArduPilot DataFlash with GPS,
    # tcpdump -i any, SavvyCAN): the same findings must come out of every format.
    frames = flight_frames()
    made["sample-dataflash.bin"] = folder / "sample-dataflash.bin"
    made["sample-dataflash.bin"].write_bytes(ardupilot_log(frames, frames[0].time - 10)[0])
    made["sample-sll2.pcap"] = sll_pcap(folder / "sample-sll2.pcap", frames, 276)
    made["sample-savvycan.csv"] = folder / "sample-savvycan.csv"
    made["sample-savvycan.csv"].write_text(savvycan_csv(frames), encoding="utf-8")
    dense = folder / "dense-mix.log"
    with dense.open("w", encoding="utf-8") as f:
        for batch in _decode_speed().dense_lines(DENSE_FRAMES):
            f.write("\n".join(batch) + "\n")
    made[dense.name] = dense
    return made
