"""The overlay at the moments pictures were taken, followed from events (the report)."""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable, Iterator
from functools import cached_property
from typing import Protocol

from analyzer.extras import VIDEO, installed
from analyzer.protocol.types import Event
from analyzer.scene.overlays import Overlay, overlay
from analyzer.scene.state import COMMAND, FEEDBACK, INPUT_TOPICS, GimbalState


class TimedPicture(Protocol):
    """A camera picture (``analyzer.mcapio.read.video.Thumbnail``)."""

    @property
    def stream(self) -> str: ...

    @property
    def time(self) -> float: ...

    @property
    def jpeg(self) -> bytes: ...


class OverlayTimeline:
    """``add`` every event in time order; ``at(t)``, for ``t`` one of the ``moments`` given
    (the pictures' times, read before the events), is the overlay shown at ``t``: the one
    after the last feedback or command at or before it, None before the first.

    Only the overlays of those moments are kept (one shared by the moments between two
    feedbacks), so memory grows with the pictures, not with the flight's feedback.
    """

    def __init__(self, moments: Iterable[float]) -> None:
        self._state = GimbalState()
        self.moments = frozenset(moments)
        self._pending = deque(sorted(self.moments))  # moments no feedback has passed yet
        self._shown: dict[float, Overlay | None] = {}
        self._current: Overlay | None = None
        self._last: float | None = None

    def add(self, event: Event) -> None:
        if event.topic in INPUT_TOPICS and self._state.observe(event) in (FEEDBACK, COMMAND):
            if self._last is not None and event.time < self._last:
                return  # out of order: the overlay of that moment is already past
            pending = self._pending
            while pending and pending[0] < event.time:  # these show the overlay before it
                self._shown[pending.popleft()] = self._current
            self._last = event.time
            # No overlay is worked out (nor kept) that no picture shows.
            self._current = overlay(self._state) if pending else None

    @property
    def kept(self) -> int:
        """How many overlays are kept (one per moment passed, and the current one)."""
        return len(self._shown) + (self._current is not None)

    def at(self, t: float) -> Overlay | None:
        if t not in self.moments:
            raise KeyError(f"{t} is not one of the moments the timeline follows")
        return self._shown.get(t, self._current)

    def pictures(self, pictures: Iterable[TimedPicture]) -> Iterator[TimedPicture]:
        """The pictures with the overlay of their moment drawn in (when they are shown); a
        picture of a moment not followed is left as it is."""
        for picture in pictures:
            shown = self.at(picture.time) if picture.time in self.moments else None
            yield picture if shown is None else OverlaidPicture(picture, shown)


class OverlaidPicture:
    """A picture whose JPEG has the overlay drawn in, drawn the first time it is asked for
    (a report shows a few of many pictures)."""

    def __init__(self, picture: TimedPicture, shown: Overlay) -> None:
        self.stream = picture.stream
        self.time = picture.time
        self.overlay = shown
        self._source = picture.jpeg

    @cached_property
    def jpeg(self) -> bytes:
        """The JPEG with the overlay drawn in (as recorded without the video extra)."""
        if not installed(VIDEO):
            return self._source
        from analyzer.scene.raster import jpeg_with_overlay  # PyAV

        return jpeg_with_overlay(self._source, self.overlay) or self._source
