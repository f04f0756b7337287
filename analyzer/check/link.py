"""The bench's one link (check, replay): a capture source that also transmits, and records
what it sends."""

from __future__ import annotations

import threading

from analyzer import wall_clock
from analyzer.errors import SourceError
from analyzer.protocol.ids import CONTROL_ID
from analyzer.protocol.types import TO_IDU, CanFrame, Event, StreamChunk
from analyzer.sim.transports import LinkSpec, SimulatedLink, open_ground_link, to_stream
from analyzer.sources.base import QueuedSource, link_event

RECEIVE_WAIT_S = 0.05


class CheckLink(QueuedSource):
    """The ground station's end of ``--to`` as a capture source (``analyzer.sources``).

    A thread receives from the link; ``send`` transmits a command on the same link and
    hands the capture the frame exactly as sent (a CAN frame, or the TCP / UART bytes
    going to the IDU), so the recording and the analysis see the commands as well as the
    answers. ``note`` hands over an event of the check's own (a step's verdict). Nothing
    is ever sent anywhere but this one link.
    """

    thread_name = "check-link"

    def __init__(
        self, spec: LinkSpec, link: SimulatedLink | None = None, purpose: str = "the check"
    ) -> None:
        super().__init__()
        self.spec = spec
        self.link = link if link is not None else open_ground_link(spec)
        self.description = self.link.name
        self.source_name = spec.channel if spec.kind == "can" else self.link.name
        self.sent = 0
        self.last_sent = 0.0  # time of the newest command sent
        self._send_lock = threading.Lock()
        self._put(link_event(self.source_name, f"opened {self.link.name} for {purpose}", "open"))
        self._start()

    def _run(self) -> None:
        while not self._stopping.is_set():
            try:
                items = self.link.receive(RECEIVE_WAIT_S)
            except SourceError as exc:
                self._fail(str(exc))
                return
            for item in items:
                if isinstance(item, CanFrame):
                    item.channel = self.source_name  # as the capture sources name channels
                self._put(item)

    def send(self, data: bytes) -> float:
        """Transmit one command's 8 data bytes; returns the time it was sent (Unix s)."""
        return self.send_frame(CONTROL_ID, data)

    def send_frame(self, can_id: int, data: bytes) -> float:
        """Transmit one frame of the ground station's (a command, or UAV status on its own
        CAN ID) in the link's framing; returns the time it was sent (Unix s)."""
        with self._send_lock:
            if self._error is not None:  # the receiving side found the link broken
                raise SourceError(self._error)
            self.link.send(can_id, data)
            now = wall_clock.now()
            self.sent += 1
            self.last_sent = now
        if self.spec.kind == "can":
            self._put(CanFrame(now, can_id, data, True, self.source_name, direction="tx"))
        else:
            self._put(StreamChunk(now, to_stream(can_id, data), self.link.name, TO_IDU))
        return now

    def note(self, event: Event) -> None:
        self._put(event)

    @property
    def failure(self) -> str | None:
        """Why the link stopped working, once it has."""
        return self._error

    def _shutdown_io(self) -> None:
        pass

    def close(self) -> None:
        super().close()
        self.link.close()
