"""Pictures to H.264 access units with PyAV's libx264: no B-frames, a keyframe every GOP."""

from __future__ import annotations

from fractions import Fraction
from typing import cast

import av
import numpy as np


class H264Encoder:
    """libx264 tuned as a camera streams: zero latency (one access unit out per picture in,
    no B-frames, which the recorder refuses), a keyframe every ``gop`` pictures with the
    parameter sets in front of it."""

    def __init__(self, width: int, height: int, fps: int, gop: int, crf: int = 23) -> None:
        self.width, self.height = width, height
        context = cast(av.VideoCodecContext, av.CodecContext.create("libx264", "w"))
        context.width, context.height = width, height
        context.pix_fmt = "yuv420p"
        context.time_base = Fraction(1, fps)
        context.framerate = Fraction(fps, 1)
        context.gop_size = gop
        context.max_b_frames = 0
        context.options = {
            "preset": "ultrafast",
            "tune": "zerolatency",
            "crf": str(crf),
            "x264-params": f"keyint={gop}:min-keyint={gop}:scenecut=0:repeat-headers=1",
        }
        self.context = context
        self.pictures = 0

    def encode(self, rgb: np.ndarray) -> list[bytes]:
        """The access units (Annex B) that the picture gives: one, with zero latency."""
        frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(rgb), format="rgb24")
        frame = frame.reformat(format="yuv420p")
        frame.pts = self.pictures
        self.pictures += 1
        return [bytes(packet) for packet in self.context.encode(frame)]

    def flush(self) -> list[bytes]:
        return [bytes(packet) for packet in self.context.encode(None)]
