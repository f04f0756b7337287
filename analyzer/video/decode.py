"""Access units to pictures: a window of a stream decoded from its keyframe (PyAV), scaled down."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol, cast

import av
import numpy as np

from analyzer.video.thumbnail import DECODERS

ANALYSIS_WIDTH = 640  # pictures are looked at this wide at most


class EncodedFrame(Protocol):
    """A frame as stored: capture time and Annex B bytes."""

    @property
    def time(self) -> float: ...

    @property
    def data(self) -> bytes: ...


@dataclass(frozen=True, slots=True)
class Picture:
    """One decoded picture: its capture time and RGB pixels (height x width x 3, uint8)."""

    time: float
    rgb: np.ndarray


def decode_window(
    codec: str,
    units: Sequence[EncodedFrame],
    start: float,
    *,
    every_s: float = 0.0,
    width: int = ANALYSIS_WIDTH,
) -> list[Picture]:
    """The pictures of ``units`` (from a keyframe on, in order) taken at ``start`` or later,
    at most ``width`` pixels wide. Every unit is decoded (each picture refers to the ones
    before it); only those ``every_s`` apart or more are converted, the last one always.
    Units that do not decode are left out (a damaged stream leaves a gap)."""
    try:
        decoder = cast(av.VideoCodecContext, av.CodecContext.create(DECODERS[codec], "r"))
    except (KeyError, av.error.FFmpegError):
        return []
    decoder.thread_type = "SLICE"  # frame threads would hold pictures back
    times = {index: unit.time for index, unit in enumerate(units)}
    last_index = len(units) - 1
    out: list[Picture] = []
    for index, unit in enumerate(units):
        packet = av.Packet(unit.data)
        packet.pts = index
        try:
            frames = decoder.decode(packet)
        except (av.error.FFmpegError, ValueError):
            continue
        for frame in frames:
            at = times.get(frame.pts if frame.pts is not None else index, unit.time)
            if at < start:
                continue
            if out and at - out[-1].time < every_s and index != last_index:
                continue
            out.append(Picture(at, _rgb(frame, width)))
    return out


def _rgb(frame: av.VideoFrame, width: int) -> np.ndarray:
    scale = min(1.0, width / max(1, frame.width))
    w = max(2, int(frame.width * scale) // 2 * 2)
    h = max(2, int(frame.height * scale) // 2 * 2)
    return frame.to_ndarray(width=w, height=h, format="rgb24", interpolation="AREA")
