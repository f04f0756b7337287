"""The simulated camera's streams, recorded like an RTSP camera's: H.264 access units in Annex B."""

from __future__ import annotations

import time

import numpy as np

from analyzer.sim.camera.encoder import H264Encoder
from analyzer.sim.camera.eye import GimbalEye
from analyzer.sim.camera.frames import MAIN, SUB, THERMAL, Gain, picture
from analyzer.sim.camera.world import make_world
from analyzer.video.annexb import H264, ParameterSets, annex_b, split_nals
from analyzer.video.rtsp_stream import VideoStream
from analyzer.video.spec import DEFAULT_THUMBNAIL_S, VideoSpec

# 15 pictures a second at 640 x 360: rendering (ray casting with OpenCV's remap) and
# encoding take about 20 ms a picture on one core of the reference machine, so the main
# stream costs about a third of a core next to the rest of the demo, and the picture has
# the detail the zoom measurement needs (it looks at 640 pixels wide at most anyway).
FPS = 15
GOP_S = 1.0  # a keyframe every second: a judgement decodes at most a second before its frame
SIZES = {MAIN: (640, 360), SUB: (320, 180), THERMAL: (320, 256)}
KINDS = {"main": MAIN, "sub1": SUB, "sub2": THERMAL, "thermal": THERMAL}


def stream_kind(name: str) -> str:
    """What the simulated camera's stream ``name`` shows (the document's subtype 2 is the
    dual-sensor camera's thermal stream)."""
    return KINDS.get(name, MAIN)


class SimulatedStream(VideoStream):
    """A stream of the simulated camera, as a VideoStream: its thread renders what the
    gimbal sees ``fps`` times a second, encodes it with libx264 and queues the access units
    (parameter sets before each keyframe, thumbnails, a bounded queue, link diagnostics)
    exactly as an RTSP camera's are queued. Frames carry their render time."""

    def __init__(
        self,
        spec: VideoSpec,
        eye: GimbalEye,
        *,
        fps: int = FPS,
        thumbnail_interval: float = DEFAULT_THUMBNAIL_S,
    ) -> None:
        super().__init__(spec, thumbnail_interval=thumbnail_interval)
        self.eye = eye
        self.fps = fps
        self.kind = stream_kind(spec.name)
        self.size = SIZES[self.kind]

    def _session(self) -> bool:
        if not self.eye.attached.wait(5.0):
            raise TimeoutError("the simulated gimbal did not start")
        world = make_world()
        width, height = self.size
        encoder = H264Encoder(width, height, self.fps, max(1, round(self.fps * GOP_S)))
        params = ParameterSets(H264)
        self.connections += 1
        self._link(
            f"connected to {self.spec.shown} (h264 {width}x{height}, {self.fps} fps)", "connected"
        )
        self._need_key = True
        gain = Gain()
        interval = 1.0 / self.fps
        next_at = time.monotonic()
        got = False
        while not self._stopping.is_set():
            delay = next_at - time.monotonic()
            if delay > 0 and self._stopping.wait(delay):
                break
            now, wall = time.monotonic(), time.time()
            shot = self.eye.shot(now)
            image = (
                picture(world, shot, self.kind, width, height, gain)
                if shot is not None
                else np.zeros((height, width, 3), np.uint8)
            )
            for data in encoder.encode(image):
                unit, key = annex_b(H264, split_nals(data), params)
                got = self._queue(wall, unit, key, H264, width, height) or got
            next_at += interval
            if next_at < time.monotonic() - interval:  # fell behind: drop pictures, not time
                next_at = time.monotonic()
        return got
