"""`demo --ardupilot`: the mount driver and the simulated gimbal on a virtual CAN bus, live."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from analyzer.ardupilot.plan import MountLibrary
from analyzer.ardupilot.script import LuaScript
from analyzer.ardupilot.vehicle import Vehicle
from analyzer.protocol.types import CanFrame, Event
from analyzer.sim.engine import SimConfig, SimulatedGimbal
from analyzer.sim.runner import SimulatorRunner
from analyzer.sim.scene import Scene
from analyzer.sim.transports import CanLink, LinkSpec, open_gimbal_link
from analyzer.sim.uav import FlightPath
from analyzer.sources.base import Source, SourceItem

MAX_WAIT_S = 0.02  # longest wait for the bus between two looks at the script's schedule
BOOT_MS = 1000  # millis() when the script starts


class AutopilotCanLink(CanLink):
    """The autopilot's CAN port: frames go out standard or extended as the script set them."""

    def send_frame(self, can_id: int, data: bytes, extended: bool) -> bool:
        msg = self._message(arbitration_id=can_id, data=data, is_extended_id=extended)
        try:
            self.bus.send(msg, timeout=0.01)
        except self._error:
            self.send_errors += 1
            return False
        return True


class NotedSource:
    """A capture source that also hands on events noted from another thread (the
    autopilot's /ardupilot/* events), with what the wrapped source reads."""

    def __init__(self, source: Source) -> None:
        self.source = source
        self.description = source.description
        self._notes: list[Event] = []
        self._lock = threading.Lock()

    def note(self, events: list[Event]) -> None:
        with self._lock:
            self._notes.extend(events)

    def read(self, timeout: float) -> list[SourceItem]:
        items = self.source.read(timeout)
        with self._lock:
            notes, self._notes = self._notes, []
        return [*items, *notes]

    def close(self) -> None:
        self.source.close()

    def __getattr__(self, name: str) -> Any:
        return getattr(self.source, name)


class ArduPilotScene(Scene):
    """The simulated gimbal and an autopilot running a driver on ``spec``: the demo's Scene
    with the autopilot in the ground station's place (start() / stop() / ``errors`` as
    there). The autopilot's events go to ``note``, what the script says to the GCS to
    ``log``; a script error ends the autopilot (in ``errors``)."""

    def __init__(
        self,
        spec: LinkSpec,
        config: SimConfig,
        script_source: str,
        script_name: str,
        *,
        note: Callable[[list[Event]], None],
        path: FlightPath | None = None,
        library: MountLibrary | None = None,
        log: Callable[[str], None] | None = None,
    ) -> None:
        gimbal_link = open_gimbal_link(spec)
        try:
            link = AutopilotCanLink(spec)
        except BaseException:
            gimbal_link.close()
            raise
        self.links: list[Any] = [gimbal_link, link]
        self.gimbal = SimulatedGimbal(time.monotonic(), config)
        self.runner = SimulatorRunner(self.gimbal, gimbal_link, status_every=None)
        vehicle = Vehicle(
            link.send_frame,
            library=library or MountLibrary(),
            path=path or FlightPath(),
            start=time.time(),
            boot_ms=BOOT_MS,
        )
        script = LuaScript(script_source, script_name, vehicle)
        self.ground: Any = Autopilot(link, script, note, log)
        self._threads = [
            threading.Thread(target=self._guard(self.runner.run), name="sim-gimbal", daemon=True),
            threading.Thread(target=self._guard(self.ground.run), name="autopilot", daemon=True),
        ]
        self.errors: list[BaseException] = []
        self._stopping = threading.Lock()


class Autopilot:
    """Runs the script in real time on the autopilot's CAN port until stopped."""

    def __init__(
        self,
        link: AutopilotCanLink,
        script: LuaScript,
        note: Callable[[list[Event]], None],
        log: Callable[[str], None] | None,
    ) -> None:
        self.link = link
        self.script = script
        self.vehicle = script.vehicle
        self.note = note
        self.log = log
        self._stop = threading.Event()
        self._texts = 0

    def stop(self) -> None:
        self._stop.set()

    def run(self) -> None:
        began = time.monotonic()

        def now_ms() -> int:
            return BOOT_MS + int((time.monotonic() - began) * 1000)

        self.vehicle.start = time.time()
        script = self.script
        try:
            script.start(now_ms())
            while not self._stop.is_set() and script.due_ms is not None:
                wait = max(0.0, min(MAX_WAIT_S, (script.due_ms - now_ms()) / 1000))
                for item in self.link.receive(wait):
                    if isinstance(item, CanFrame):
                        self.vehicle.deliver(item.can_id, item.data, item.extended)
                if script.due_ms is not None and now_ms() >= script.due_ms:
                    script.run(now_ms())
                self._hand_on()
        finally:
            self._hand_on()

    def _hand_on(self) -> None:
        events = self.vehicle.take_events()
        if events:
            self.note(events)
        texts = self.vehicle.texts
        while self._texts < len(texts):
            _, _, text = texts[self._texts]
            self._texts += 1
            if self.log is not None:
                self.log(f"ardupilot: {text}")
