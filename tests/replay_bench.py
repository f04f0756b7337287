"""A demo flight and a replay of it to a simulated gimbal in virtual time, recorded to MCAP.

The flight is a pilot's session (``analyzer.sim.pilot_session``: three stick movements, a
target re-sent for 3 s, a tracker) played against a simulated gimbal with the UAV's
status on the bus, written as ``candump -L`` would. The replay runs the same player
``gimbal-analyzer replay`` runs, on ``analyzer.check.offline.SimulatedBench`` (the
check's runner on a simulated gimbal in virtual time), and records what its pipeline
sees as the command records a live one: the response analysis and an MCAP sink.
"""

from __future__ import annotations

from pathlib import Path

from analyzer.check.offline import SimulatedBench
from analyzer.commands.input_pass import read_through
from analyzer.mcapio.write.sink import McapSink, recording_metadata
from analyzer.replay.flight import FlightReader, Span, span_of
from analyzer.replay.player import Outcome, Player
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.engine import SimConfig
from analyzer.sim.offline import run_offline
from analyzer.sim.pilot_session import START, pilot_steps

SECONDS = 36.0


def write_flight(path: Path, behaviour: Behaviour | None = None) -> Path:
    """The demo flight as a candump log: the pilot's commands, the gimbal's feedback and
    the UAV's status (GPS, altitude, attitude, a text) on one bus."""
    config = SimConfig(uav=True, behaviour=behaviour or Behaviour())
    frames, _ = run_offline(pilot_steps(), SECONDS, config, start=START, channel="can0")
    lines = [f"({f.time:.6f}) can0 {f.can_id:08X}#{f.data.hex().upper()}" for f in frames]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def read_span(flight: Path, start_s: float = 0.0, end_s: float | None = None) -> Span:
    reader = FlightReader()
    read_through(str(flight), [reader], quiet=True)
    return span_of(reader, str(flight), start_s, end_s)


def replay_offline(
    span: Span,
    output: Path,
    config: SimConfig | None = None,
    *,
    speed: float = 1.0,
    align: bool = True,
) -> tuple[Outcome, SimulatedBench]:
    """``span`` replayed to a simulated gimbal in virtual time, recorded to ``output``."""
    bench = SimulatedBench(config or SimConfig())
    sink = McapSink(
        output, metadata=recording_metadata(f"replay: {span.source} over sim", command="replay")
    )
    bench.pipeline.sinks.append(sink)
    player = Player(bench, bench.observer, source="sim", clock=bench)
    outcome = player.play(span, speed=speed, align=align)
    player.centre(wait=True)
    bench.finish()  # closes the sinks: the recording is finished
    return outcome, bench
