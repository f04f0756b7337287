"""`demo --ardupilot`: the mount driver and the simulated gimbal on a virtual CAN bus, live."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from analyzer.ardupilot.plan import MountLibrary
from analyzer.ardupilot.script import LuaScript, ScriptFailed
from analyzer.ardupilot.vehicle import Vehicle
from analyzer.protocol.types import CanFrame, Event
from analyzer.sim.engine import SimConfig, SimulatedGimbal
from analyzer.sim.runner import SimulatorRunner
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


class ArduPilotScene:
    """The simulated gimbal and an autopilot running ``driver`` on ``spec``; start() /
    stop(), like the demo's Scene. The autopilot's events go to ``note``; what the script
    says to the GCS goes to ``log``; a script error ends the autopilot (``errors``)."""

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
        self.errors: list[BaseException] = []
        self.note = note
        self.log = log
        self._stop = threading.Event()
        gimbal_link = open_gimbal_link(spec)
        try:
            self.link = AutopilotCanLink(spec)
        except BaseException:
            gimbal_link.close()
            raise
        self.links: list[Any] = [gimbal_link, self.link]
        self.start_time = time.time()
        self.gimbal = SimulatedGimbal(time.monotonic(), config)
        self.runner = SimulatorRunner(self.gimbal, gimbal_link, status_every=None)
        self.vehicle = Vehicle(
            self.link.send_frame,
            library=library or MountLibrary(),
            path=path or FlightPath(),
            start=self.start_time,
            boot_ms=BOOT_MS,
        )
        self.script = LuaScript(script_source, script_name, self.vehicle)
        self._texts = 0
        self._threads = [
            threading.Thread(target=self._guard(self.runner.run), name="sim-gimbal", daemon=True),
            threading.Thread(target=self._guard(self._fly), name="autopilot", daemon=True),
        ]
        self._stopping = threading.Lock()

    def _guard(self, body: Callable[[], None]) -> Callable[[], None]:
        def run() -> None:
            try:
                body()
            except Exception as exc:  # a link failed or the script stopped
                self.errors.append(exc)

        return run

    def _fly(self) -> None:
        began = time.monotonic()

        def now_ms() -> int:
            return BOOT_MS + int((time.monotonic() - began) * 1000)

        self.start_time = time.time()
        self.vehicle.start = self.start_time
        try:
            self.script.start(now_ms())
            while not self._stop.is_set() and self.script.due_ms is not None:
                wait = max(0.0, min(MAX_WAIT_S, (self.script.due_ms - now_ms()) / 1000))
                for item in self.link.receive(wait):
                    if isinstance(item, CanFrame):
                        self.vehicle.deliver(item.can_id, item.data, item.extended)
                if self.script.due_ms is not None and now_ms() >= self.script.due_ms:
                    self.script.run(now_ms())
                self._hand_on()
        except ScriptFailed:
            self._hand_on()
            raise
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

    def start(self) -> None:
        for thread in self._threads:
            thread.start()

    def stop(self, timeout: float = 2.0) -> None:
        """Stop both threads and close the links; safe to call twice, from any thread."""
        self.runner.stop()
        self._stop.set()
        with self._stopping:
            for thread in self._threads:
                if thread.is_alive() and thread is not threading.current_thread():
                    thread.join(timeout)
            links, self.links = self.links, []
        for link in links:
            link.close()
