"""The overlay over time, followed from events, for pictures taken at any moment (the report)."""

from __future__ import annotations

import bisect
from collections.abc import Iterable, Iterator
from functools import cached_property
from typing import Protocol

from analyzer.protocol.types import Event
from analyzer.scene.overlays import Overlay, overlay
from analyzer.scene.state import COMMAND, FEEDBACK, INPUT_TOPICS, GimbalState


class Picture(Protocol):
    """A camera picture (``analyzer.mcapio.read.video.Thumbnail``)."""

    @property
    def stream(self) -> str: ...

    @property
    def time(self) -> float: ...

    @property
    def jpeg(self) -> bytes: ...


class OverlayTimeline:
    """``add`` every event in time order; ``at(t)`` is the overlay shown at ``t`` (the one
    after the last feedback or command before it, None before the first)."""

    def __init__(self) -> None:
        self._state = GimbalState()
        self._times: list[float] = []
        self._overlays: list[Overlay] = []

    def add(self, event: Event) -> None:
        if event.topic in INPUT_TOPICS and self._state.observe(event) in (FEEDBACK, COMMAND):
            if self._times and event.time < self._times[-1]:
                return  # out of order: the overlay of that moment is already past
            self._times.append(event.time)
            self._overlays.append(overlay(self._state))

    def at(self, t: float) -> Overlay | None:
        i = bisect.bisect_right(self._times, t)
        return self._overlays[i - 1] if i else None

    def pictures(self, pictures: Iterable[Picture]) -> Iterator[Picture]:
        """The pictures with the overlay of their moment drawn in (when they are shown)."""
        for picture in pictures:
            shown = self.at(picture.time)
            yield picture if shown is None else OverlaidPicture(picture, shown)


class OverlaidPicture:
    """A picture whose JPEG has the overlay drawn in, drawn the first time it is asked for
    (a report shows a few of many pictures)."""

    def __init__(self, picture: Picture, shown: Overlay) -> None:
        self.stream = picture.stream
        self.time = picture.time
        self.overlay = shown
        self._source = picture.jpeg

    @cached_property
    def jpeg(self) -> bytes:
        from analyzer.scene.raster import jpeg_with_overlay  # PyAV: pictures need it anyway

        return jpeg_with_overlay(self._source, self.overlay) or self._source
