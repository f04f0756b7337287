"""A mount driver against the simulated gimbal in virtual time: no IO, no waiting."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from analyzer.ardupilot.plan import DEMO_PERIOD, DEMO_PLAN, MountLibrary, Step
from analyzer.ardupilot.script import LuaScript, ScriptFailed
from analyzer.ardupilot.vehicle import Vehicle
from analyzer.protocol.decoder import Decoder
from analyzer.protocol.types import CanFrame, Event
from analyzer.sim.engine import SimConfig, SimulatedGimbal
from analyzer.sim.uav import FlightPath

BOOT_MS = 1000  # the script starts this long after the autopilot boots


@dataclass
class Session:
    """What a run gave: the bus as a capture holds it, the events decoded from it plus the
    /ardupilot/* events, and the autopilot and script as they ended."""

    frames: list[CanFrame]
    events: list[Event]
    vehicle: Vehicle
    script: LuaScript
    error: str | None = None
    gimbal: SimulatedGimbal | None = None
    sent: list[CanFrame] = field(default_factory=list)  # what the script wrote


def run_session(
    source: str,
    name: str,
    duration: float,
    *,
    plan: tuple[Step, ...] = DEMO_PLAN,
    period: float | None = DEMO_PERIOD,
    config: SimConfig | None = None,
    path: FlightPath | None = None,
    parameters: dict[str, float] | None = None,
    gimbal: bool = True,
    start: float = 0.0,
    channel: str = "sim",
) -> Session:
    """Run the driver ``source`` for ``duration`` seconds of the autopilot's time.

    The simulated gimbal (``config``; it does not play the UAV: the driver's status
    frames are the only ones) shares the bus with the driver; without ``gimbal`` the
    bus is silent. A script error ends the run early (``error``)."""
    frames: list[CanFrame] = []
    sent: list[CanFrame] = []
    events: list[Event] = []
    decoder = Decoder()
    sim = SimulatedGimbal(start, config or SimConfig(ranging=True)) if gimbal else None
    clock = {"now": start}

    def on_bus(can_id: int, data: bytes, extended: bool) -> bool:
        frame = CanFrame(clock["now"], can_id, bytes(data), extended, channel)
        frames.append(frame)
        sent.append(frame)
        for event in decoder.feed(frame):
            events.append(event)
            if sim is not None and extended:
                sim.handle(event, clock["now"])
        return True

    vehicle = Vehicle(
        on_bus,
        library=MountLibrary(plan, period),
        path=path or FlightPath(),
        parameters=parameters,
        start=start,
        boot_ms=BOOT_MS,
    )
    script = LuaScript(source, name, vehicle)
    error = None
    end_ms = BOOT_MS + round(duration * 1000)
    now_ms = BOOT_MS
    try:
        script.start(now_ms)
        while now_ms <= end_ms:
            clock["now"] = start + (now_ms - BOOT_MS) / 1000
            vehicle.advance(now_ms)
            if sim is not None:
                for can_id, data in sim.poll(clock["now"]):
                    frame = CanFrame(clock["now"], can_id, data, True, channel)
                    frames.append(frame)
                    events.extend(decoder.feed(frame))
                    vehicle.deliver(can_id, data)
            if script.due_ms is not None and now_ms >= script.due_ms:
                script.run(now_ms)
            events.extend(vehicle.take_events())
            now_ms = _next_ms(now_ms, script, sim, start)
    except ScriptFailed as exc:
        error = str(exc)
    events.extend(vehicle.take_events())
    events.extend(decoder.close(start + duration))
    events.sort(key=lambda e: e.time)
    return Session(frames, events, vehicle, script, error, sim, sent)


def _next_ms(now_ms: int, script: LuaScript, sim: SimulatedGimbal | None, start: float) -> int:
    times = [now_ms + 1000]
    if script.due_ms is not None:
        times.append(script.due_ms)
    if sim is not None:
        times.append(BOOT_MS + math.ceil((sim.next_time() - start) * 1000 - 1e-6))
    return max(now_ms + 1, min(times))
