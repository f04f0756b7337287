"""The simulated camera's streams: pictures rendered in time, H.264, queued as an RTSP camera's."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

import numpy as np

from analyzer.sim.camera.encoder import H264Encoder
from analyzer.sim.camera.eye import GimbalEye
from analyzer.sim.camera.frames import MAIN, SUB, THERMAL, Gain, picture
from analyzer.sim.camera.world import make_world
from analyzer.video.annexb import H264, ParameterSets, annex_b, split_nals
from analyzer.video.rtsp_stream import VideoStream
from analyzer.video.spec import DEFAULT_THUMBNAIL_S, VideoSpec

# 15 pictures a second at 640 x 360: rendering (ray casting with OpenCV's remap) and
# encoding take about 10 ms a picture on one core of the reference machine, so the main
# stream costs about a sixth of a core next to the rest of the demo, and the picture has
# the detail the zoom measurement needs (it looks at 640 pixels wide at most anyway).
FPS = 15
GOP_S = 1.0  # a keyframe every second: a judgement decodes at most a second before its frame
SIZES = {MAIN: (640, 360), SUB: (320, 180), THERMAL: (320, 256)}
KINDS = {"main": MAIN, "sub1": SUB, "sub2": THERMAL, "thermal": THERMAL}

# deliver(capture time, Annex B access unit, keyframe): where a rendered picture goes
Deliver = Callable[[float, bytes, bool], None]


def stream_kind(name: str) -> str:
    """What the simulated camera's stream ``name`` shows (the document's subtype 2 is the
    dual-sensor camera's thermal stream)."""
    return KINDS.get(name, MAIN)


class Filming:
    """One stream of the simulated camera in real time: ``fps`` times a second the gimbal's
    view is rendered, encoded with libx264 (parameter sets before each keyframe, Annex B)
    and handed to ``deliver`` with its render time (Unix seconds). A late picture is
    dropped, not the clock."""

    def __init__(self, eye: GimbalEye, kind: str, fps: int = FPS) -> None:
        self.eye = eye
        self.kind = kind
        self.fps = fps
        self.size = SIZES[kind]

    def run(self, stopping: threading.Event, deliver: Deliver) -> None:
        if not self.eye.attached.wait(5.0):
            raise TimeoutError("the simulated gimbal did not start")
        world = make_world()
        width, height = self.size
        encoder = H264Encoder(width, height, self.fps, max(1, round(self.fps * GOP_S)))
        params = ParameterSets(H264)
        gain = Gain()
        interval = 1.0 / self.fps
        next_at = time.monotonic()
        while not stopping.is_set():
            delay = next_at - time.monotonic()
            if delay > 0 and stopping.wait(delay):
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
                deliver(wall, unit, key)
            next_at += interval
            if next_at < time.monotonic() - interval:  # fell behind: drop pictures, not time
                next_at = time.monotonic()


class SimulatedStream(VideoStream):
    """A stream of the simulated camera, as a VideoStream: its thread films what the
    gimbal sees and queues the access units exactly as an RTSP camera's are queued
    (thumbnails, a bounded queue, link diagnostics). Frames carry their render time."""

    def __init__(
        self,
        spec: VideoSpec,
        eye: GimbalEye,
        *,
        fps: int = FPS,
        thumbnail_interval: float = DEFAULT_THUMBNAIL_S,
    ) -> None:
        super().__init__(spec, thumbnail_interval=thumbnail_interval)
        self.filming = Filming(eye, stream_kind(spec.name), fps)

    def _session(self) -> bool:
        width, height = self.filming.size
        self.connections += 1
        self._link(
            f"connected to {self.spec.shown} (h264 {width}x{height}, {self.filming.fps} fps)",
            "connected",
        )
        self._need_key = True
        got = [False]

        def deliver(wall: float, unit: bytes, key: bool) -> None:
            got[0] = self._queue(wall, unit, key, H264, width, height) or got[0]

        self.filming.run(self._stopping, deliver)
        return got[0]
