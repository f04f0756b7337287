"""The pictures of a live recording: the camera's recent access units kept as they are recorded."""

from __future__ import annotations

import bisect
from collections import deque
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from analyzer.analysis.camera.source import PICTURE_EVERY_S
from analyzer.video.decode import Picture, decode_window

KEEP_S = 30.0  # the video kept for judgements still to come


@dataclass(frozen=True, slots=True)
class _Unit:
    time: float
    data: bytes
    keyframe: bool
    codec: str


class LiveVideo:
    """A VideoSource fed with the frames a live recorder writes (``add``, in the capture's
    thread, which also runs the judgement); the last KEEP_S seconds of each stream."""

    def __init__(self, names: Sequence[str]) -> None:
        self._names = list(names)
        self._units: dict[str, deque[_Unit]] = {name: deque() for name in names}

    def add(self, frames: Iterable[object]) -> None:
        """Frames as the recorder got them (``VideoFrame``: stream, time, data, keyframe)."""
        for frame in frames:
            name = str(getattr(frame, "stream", ""))
            units = self._units.setdefault(name, deque())
            unit = _Unit(
                float(getattr(frame, "time", 0.0)),
                bytes(getattr(frame, "data", b"")),
                bool(getattr(frame, "keyframe", False)),
                str(getattr(frame, "codec", "h264")),
            )
            units.append(unit)
            while units and units[-1].time - units[0].time > KEEP_S:
                units.popleft()

    def streams(self) -> list[str]:
        return sorted(self._names)

    def pictures(self, stream: str, start: float, end: float) -> list[Picture]:
        units = sorted(self._units.get(stream, ()), key=lambda u: u.time)
        times = [u.time for u in units]
        stop = bisect.bisect_right(times, end)
        first = bisect.bisect_right(times, start)
        keys = [i for i in range(min(first, stop)) if units[i].keyframe]
        begin = keys[-1] if keys else next((i for i in range(stop) if units[i].keyframe), stop)
        window = units[begin:stop]
        if not window:
            return []
        return decode_window(window[0].codec, window, start, every_s=PICTURE_EVERY_S)

    def until(self) -> float:
        """The newest frame of the stream that is furthest behind (-inf before any)."""
        newest = [units[-1].time for units in self._units.values() if units]
        return min(newest) if newest else float("-inf")
