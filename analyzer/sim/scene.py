"""A simulated gimbal and a scripted ground station sharing one link, each in its own thread."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Protocol

from analyzer.sim.engine import SimConfig, SimulatedGimbal
from analyzer.sim.ground import GroundScript, GroundStation
from analyzer.sim.runner import SimulatorRunner
from analyzer.sim.transports import LinkSpec, SimulatedLink, open_gimbal_link, open_ground_link


class Ground(Protocol):
    """What plays the ground station's part in its own thread: run() until stop()."""

    def run(self) -> None: ...

    def stop(self) -> None: ...


class Scene:
    """Gimbal + ground station on ``spec`` (a virtual CAN bus in the demo); start() / stop().

    The gimbal's link is opened first, so with TCP the ground station connects to it.
    ``ground`` makes another party on the ground station's link (``open_ground`` opens
    that link), in the scripted ground station's place.
    """

    def __init__(
        self,
        spec: LinkSpec,
        config: SimConfig | None = None,
        *,
        script: GroundScript | None = None,
        log: Callable[[str], None] | None = None,
        ground: Callable[[SimulatedLink], Ground] | None = None,
        open_ground: Callable[[LinkSpec], SimulatedLink] = open_ground_link,
    ) -> None:
        self.links: list[SimulatedLink] = []
        gimbal_link = open_gimbal_link(spec)
        self.links.append(gimbal_link)
        try:
            ground_spec = spec
            address = getattr(gimbal_link, "address", None)
            if address is not None:  # a TCP server on port 0: connect to the port it got
                ground_spec = LinkSpec("tcp", host=address[0], port=address[1])
            ground_link = open_ground(ground_spec)
            self.links.append(ground_link)
            self.ground: Ground = (
                GroundStation(ground_link, script) if ground is None else ground(ground_link)
            )
        except BaseException:
            for link in self.links:
                link.close()
            raise
        self.gimbal = SimulatedGimbal(time.monotonic(), config)
        self.runner = SimulatorRunner(self.gimbal, gimbal_link, log=log, status_every=None)
        self._threads = [
            threading.Thread(target=self._guard(self.runner.run), name="sim-gimbal", daemon=True),
            threading.Thread(target=self._guard(self.ground.run), name="sim-ground", daemon=True),
        ]
        self.errors: list[BaseException] = []
        self._stopping = threading.Lock()

    def _guard(self, body: Callable[[], None]) -> Callable[[], None]:
        def run() -> None:
            try:
                body()
            except Exception as exc:  # a link failed: keep the reason for the caller
                self.errors.append(exc)

        return run

    def start(self) -> None:
        for thread in self._threads:
            thread.start()

    def stop(self, timeout: float = 2.0) -> None:
        """Stop both threads and close the links; safe to call twice, from any thread."""
        self.runner.stop()
        self.ground.stop()
        with self._stopping:
            for thread in self._threads:
                if thread.is_alive() and thread is not threading.current_thread():
                    thread.join(timeout)
            links, self.links = self.links, []
        for link in links:
            link.close()

    def __enter__(self) -> Scene:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()
