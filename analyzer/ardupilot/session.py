"""A mount driver against the simulated gimbal in virtual time: no IO, no waiting."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import ModuleType

from analyzer.ardupilot.autopilot import BOOT_MS, Autopilot
from analyzer.ardupilot.plan import DEMO_PERIOD, DEMO_PLAN, MountLibrary, Step
from analyzer.ardupilot.script import LuaScript
from analyzer.ardupilot.vehicle import Vehicle
from analyzer.protocol.decoder import ProtocolDecoder
from analyzer.protocol.types import CanFrame, Event
from analyzer.sim.engine import SimConfig, SimulatedGimbal
from analyzer.sim.uav import FlightPath


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
    boot_ms: int = BOOT_MS,
    lua: ModuleType | None = None,
) -> Session:
    """Run the driver ``source`` for ``duration`` seconds of the autopilot's time, its
    millis() starting at ``boot_ms``, in ``lua`` (lupa's Lua 5.3 unless given).

    The simulated gimbal (``config``; it does not play the UAV: the driver's status
    frames are the only ones) shares the bus with the driver; without ``gimbal`` the
    bus is silent. A script error ends the run early (``error``)."""
    frames: list[CanFrame] = []
    sent: list[CanFrame] = []
    events: list[Event] = []
    decoder = ProtocolDecoder()
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

    autopilot = Autopilot(
        source,
        name,
        on_bus,
        library=MountLibrary(plan, period),
        path=path,
        parameters=parameters,
        start=start,
        boot_ms=boot_ms,
        lua=lua,
    )
    error = None
    end_ms = boot_ms + round(duration * 1000)
    now_ms = boot_ms
    while now_ms <= end_ms:
        clock["now"] = start + (now_ms - boot_ms) / 1000
        received = []
        if sim is not None:
            for can_id, data in sim.poll(clock["now"]):
                frame = CanFrame(clock["now"], can_id, data, True, channel)
                frames.append(frame)
                events.extend(decoder.feed(frame))
                received.append(frame)
        stepped = autopilot.step(now_ms, received)
        events.extend(stepped.events)
        if stepped.error is not None:
            error = stepped.error
            break
        times = [now_ms + 1000]
        if stepped.due_ms is not None:
            times.append(stepped.due_ms)
        if sim is not None:
            times.append(boot_ms + math.ceil((sim.next_time() - start) * 1000 - 1e-6))
        now_ms = max(now_ms + 1, min(times))
    events.extend(decoder.close(start + duration))
    events.sort(key=lambda e: e.time)
    return Session(frames, events, autopilot.vehicle, autopilot.script, error, sim, sent)
