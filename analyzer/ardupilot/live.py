"""`demo --ardupilot`: the mount driver and the simulated gimbal on a virtual CAN bus, live."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

from analyzer.ardupilot import lua_build
from analyzer.ardupilot.autopilot import BOOT_MS, Autopilot
from analyzer.ardupilot.plan import MountLibrary
from analyzer.ardupilot.script import ScriptFailed, compile_check
from analyzer.errors import UsageError
from analyzer.protocol.types import CanFrame, Event
from analyzer.sim.engine import SimConfig
from analyzer.sim.scene import Scene
from analyzer.sim.transports import LinkSpec, SimulatedCanLink, SimulatedLink
from analyzer.sim.uav import FlightPath
from analyzer.sources.base import Source, SourceItem

MAX_WAIT_S = 0.02  # longest wait for the bus between two looks at the script's schedule


@dataclass(frozen=True)
class DriverFile:
    """A driver the demo runs: its text, its file name, and the Lua to run it in (None:
    lupa's own)."""

    text: str
    name: str
    lua: ModuleType | None = None


def load_driver(path: str, interpreter: str, say: Callable[[str], None]) -> DriverFile:
    """The driver at ``path``, compiled in ``interpreter`` (demo --lua: "lupa" or "ardupilot",
    built once, saying so): a UsageError, in one line, when it cannot be."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise UsageError(f"--ardupilot {path}: cannot read it: {exc}") from None
    lua = None
    if interpreter == "ardupilot":
        try:
            lua = lua_build.load(lua_build.build(say=say))
        except (lua_build.BuildError, OSError, ImportError) as exc:
            raise UsageError(f"--lua ardupilot: cannot build ArduPilot's Lua: {exc}") from None
    name = Path(path).name
    try:
        compile_check(text, name, lua=lua)
    except ScriptFailed as exc:
        raise UsageError(f"--ardupilot {path}: {exc}") from None
    return DriverFile(text, name, lua)


class AutopilotCanLink(SimulatedCanLink):
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
    ``log``; a script error ends the autopilot (in ``errors``). ``lua`` is the interpreter
    (lupa's Lua 5.3 unless given)."""

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
        lua: ModuleType | None = None,
    ) -> None:
        def autopilot(link: SimulatedLink) -> AutopilotRunner:
            assert isinstance(link, AutopilotCanLink)
            machine = Autopilot(
                script_source,
                script_name,
                link.send_frame,
                library=library or MountLibrary(),
                path=path or FlightPath(),
                lua=lua,
            )
            return AutopilotRunner(link, machine, note, log)

        super().__init__(spec, config, ground=autopilot, open_ground=AutopilotCanLink)


class AutopilotRunner:
    """The wall-clock driver of an Autopilot: runs it in real time on the autopilot's CAN
    port until stopped (millis() counts from BOOT_MS; events are timed by the wall clock)."""

    def __init__(
        self,
        link: AutopilotCanLink,
        autopilot: Autopilot,
        note: Callable[[list[Event]], None],
        log: Callable[[str], None] | None,
    ) -> None:
        self.link = link
        self.autopilot = autopilot
        self.note = note
        self.log = log
        self._stop = threading.Event()

    def stop(self) -> None:
        self._stop.set()

    def run(self) -> None:
        began = time.monotonic()

        def now_ms() -> int:
            return BOOT_MS + int((time.monotonic() - began) * 1000)

        vehicle = self.autopilot.vehicle
        vehicle.start = time.time()
        vehicle.wall_clock = time.time
        due: int | None = now_ms()
        while not self._stop.is_set() and due is not None:
            wait = max(0.0, min(MAX_WAIT_S, (due - now_ms()) / 1000))
            received = [item for item in self.link.receive(wait) if isinstance(item, CanFrame)]
            stepped = self.autopilot.step(now_ms(), received)
            if stepped.events:
                self.note(stepped.events)
            self._say(*stepped.texts)
            if stepped.error is not None:
                raise ScriptFailed(stepped.error)
            due = stepped.due_ms
        script = self.autopilot.script
        self._say(
            f"Lua heap {script.heap_loaded / 1024:.0f} kB once loaded, "
            f"{script.heap_peak / 1024:.0f} kB at most after a run"
        )

    def _say(self, *texts: str) -> None:
        if self.log is not None:
            for text in texts:
                self.log(f"ardupilot: {text}")
