"""The autopilot around a Lua script, sans-IO: ``step(now_ms, received)`` moves its clock,
hands the script the frames received and runs it when due. A virtual-time driver
(session.py) and a wall-clock one (live.py) give it time and frames."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from types import ModuleType

from analyzer.ardupilot.plan import MountLibrary
from analyzer.ardupilot.script import LuaScript, ScriptFailed
from analyzer.ardupilot.userdata import Transmit
from analyzer.ardupilot.vehicle import Vehicle
from analyzer.protocol.types import CanFrame, Event
from analyzer.sim.uav import FlightPath

BOOT_MS = 1000  # millis() when the script starts


@dataclass
class Stepped:
    """What a step gave: the /ardupilot/* events, what the script said to the GCS, when the
    next run is due (None once the script ended or failed) and the error that ended it."""

    events: list[Event]
    texts: list[str]
    due_ms: int | None
    error: str | None = None


class Autopilot:
    """A script ``name`` (Lua ``source``) on an emulated autopilot whose CAN frames go to
    ``transmit``; ``lua`` is the interpreter (lupa's Lua 5.3 unless given). Its clock,
    millis(), reads ``boot_ms`` at the first step."""

    def __init__(
        self,
        source: str,
        name: str,
        transmit: Transmit,
        *,
        library: MountLibrary | None = None,
        path: FlightPath | None = None,
        parameters: dict[str, float] | None = None,
        start: float = 0.0,
        boot_ms: int = BOOT_MS,
        lua: ModuleType | None = None,
    ) -> None:
        self.vehicle = Vehicle(
            transmit,
            library=library,
            path=path,
            parameters=parameters,
            start=start,
            boot_ms=boot_ms,
        )
        self.script = LuaScript(source, name, self.vehicle, lua=lua)
        self.started = False
        self._texts = 0

    def step(self, now_ms: int, received: Iterable[CanFrame] = ()) -> Stepped:
        """The clock stands at ``now_ms``: deliver ``received`` to the scripting CAN
        buffers, then run the script if it is due. The first step loads the script (its
        chunk runs) before the frames arrive."""
        vehicle, script = self.vehicle, self.script
        vehicle.advance(now_ms)
        error = None
        try:
            if not self.started:
                self.started = True
                script.start(now_ms)
            for frame in received:
                vehicle.deliver(frame.can_id, frame.data, frame.extended)
            if script.due_ms is not None and now_ms >= script.due_ms:
                script.run(now_ms)
        except ScriptFailed as exc:
            error = str(exc)
        texts = [text for _, _, text in vehicle.texts[self._texts :]]
        self._texts = len(vehicle.texts)
        return Stepped(vehicle.take_events(), texts, script.due_ms, error)
