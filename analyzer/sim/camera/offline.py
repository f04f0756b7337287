"""A simulated flight with the simulated camera's video, in virtual time, as a recording."""

from __future__ import annotations

import copy
import functools
import json
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import cv2

from analyzer.sim.camera.encoder import H264Encoder
from analyzer.sim.camera.eye import shot_of
from analyzer.sim.camera.frames import Gain, picture
from analyzer.sim.camera.stream import FPS, GOP_S, SIZES, stream_kind
from analyzer.sim.camera.world import World, make_world
from analyzer.sim.engine import SimConfig, SimulatedGimbal
from analyzer.sim.ground import Step
from analyzer.video.annexb import H264, ParameterSets, annex_b, split_nals
from analyzer.video.rtsp_stream import VideoFrame
from analyzer.video.spec import DEFAULT_THUMBNAIL_S
from analyzer.video.thumbnail import jpeg_thumbnail

if TYPE_CHECKING:
    from analyzer.mcapio.write.channel_registry import ChannelRegistry
    from analyzer.mcapio.write.sink import McapSink
    from analyzer.protocol.types import CanFrame

BATCH_S = 0.5  # the recording is written half a second of flight at a time


@dataclass
class _Camera:
    """One stream of the simulated camera, rendered and encoded as the flight goes."""

    name: str
    size: tuple[int, int]
    fps: int
    encoder: H264Encoder
    gain: Gain = field(default_factory=Gain)
    params: ParameterSets = field(default_factory=lambda: ParameterSets(H264))
    next_at: float = 0.0
    last_thumbnail: float = float("-inf")


def record_offline(
    path: str | os.PathLike[str],
    steps: tuple[Step, ...],
    duration: float,
    config: SimConfig | None = None,
    *,
    streams: Sequence[str] = ("main",),
    fps: int = FPS,
    size: tuple[int, int] | None = None,
    start: float = 1_700_000_000.0,
    gaps: Sequence[tuple[float, float]] = (),
    thumbnail_interval: float = DEFAULT_THUMBNAIL_S,
    encoded: tuple[int, int] | None = None,
    gop_s: float = GOP_S,
) -> list[VideoFrame]:
    """Play ``steps`` against the simulated gimbal (and UAV, as ``config`` says) for
    ``duration`` seconds of virtual time and write the recording ``demo --video`` would:
    the CAN traffic, the decoded events and findings, and the simulated camera's
    ``streams`` (``size`` instead of each stream's own). ``gaps`` are (from, to) seconds
    after the start when the camera delivered nothing (the stream was lost). ``encoded``:
    the pictures are scaled to that size before encoding (a 1080p stream without rendering
    1080p), a keyframe every ``gop_s``. Returns the video frames written."""
    from analyzer.sim.offline import run_offline

    cameras = [_camera(name, fps, size, encoded, gop_s) for name in streams]
    filming = _Filming(make_world(), cameras, start, gaps, thumbnail_interval)
    items, _ = run_offline(steps, duration, config, start=start, watch=filming.watch)
    sink = _recording_sink(path, cameras)
    _interleave(sink, items, filming.frames, start)
    return filming.frames


def _camera(
    name: str,
    fps: int,
    size: tuple[int, int] | None,
    encoded: tuple[int, int] | None,
    gop_s: float,
) -> _Camera:
    """One stream of the simulated camera with its encoder."""
    width, height = size or SIZES[stream_kind(name)]
    out_w, out_h = encoded or (width, height)
    encoder = H264Encoder(out_w, out_h, fps, max(1, round(fps * gop_s)))
    return _Camera(name, (width, height), fps, encoder)


@dataclass
class _Filming:
    """The simulated camera's streams filming the flight: each picture rendered from the
    gimbal's pose, scaled and encoded as the virtual time passes (``watch``)."""

    world: World
    cameras: list[_Camera]
    start: float
    gaps: Sequence[tuple[float, float]]
    thumbnail_interval: float
    frames: list[VideoFrame] = field(default_factory=list)

    def watch(self, now: float, gimbal: SimulatedGimbal) -> None:
        elapsed = now - self.start
        for camera in self.cameras:
            if elapsed + 1e-9 < camera.next_at:
                continue
            camera.next_at += 1.0 / camera.fps
            if any(a <= elapsed < b for a, b in self.gaps):
                continue
            self._film(camera, now, gimbal)

    def _film(self, camera: _Camera, now: float, gimbal: SimulatedGimbal) -> None:
        model = copy.copy(gimbal.model)
        pose = gimbal.uav.pose(now) if gimbal.uav is not None else model.uav
        shot = shot_of(model, pose)
        width, height = camera.size
        image = picture(self.world, shot, stream_kind(camera.name), width, height, camera.gain)
        out_w, out_h = camera.encoder.width, camera.encoder.height
        if (out_w, out_h) != (width, height):
            image = cv2.resize(image, (out_w, out_h), interpolation=cv2.INTER_LINEAR)
        for data in camera.encoder.encode(image):
            unit, key = annex_b(H264, split_nals(data), camera.params)
            thumbnail = None
            due = now - camera.last_thumbnail >= self.thumbnail_interval - 0.05
            if key and self.thumbnail_interval > 0 and due:
                thumbnail = jpeg_thumbnail(H264, unit)
                camera.last_thumbnail = now
            self.frames.append(
                VideoFrame(camera.name, now, unit, key, H264, width, height, thumbnail)
            )


def _recording_sink(path: str | os.PathLike[str], cameras: list[_Camera]) -> McapSink:
    """The recording ``demo --video`` writes, with a camera and an overlay per stream."""
    from analyzer.mcapio.write.sink import McapSink, recording_metadata
    from analyzer.mcapio.write.video import VIDEO_METADATA_KEY, annotations_topic

    shown = {c.name: f"the simulated camera's {c.name} stream" for c in cameras}
    sink = McapSink(
        path,
        metadata=recording_metadata(
            "offline: simulated gimbal, ground station and camera in virtual time",
            command="demo",
            **{VIDEO_METADATA_KEY: json.dumps(shown)},
        ),
        flush_interval=None,
    )
    for camera in cameras:
        sink.add_camera(camera.name)
        sink.add_overlay(
            annotations_topic(camera.name), camera.encoder.width, camera.encoder.height
        )
    return sink


def _interleave(
    sink: McapSink, items: list[CanFrame], frames: list[VideoFrame], start: float
) -> None:
    """The flight's bus traffic through the analysis into ``sink``, and the video frames
    beside it, half a second of flight at a time, in time order."""
    from analyzer.analysis.stage import Analysis
    from analyzer.pipeline import Pipeline

    pipeline = Pipeline([sink], stages=Analysis().stages())
    items.sort(key=lambda item: item.time)
    frames.sort(key=lambda frame: frame.time)
    item_at = frame_at = 0
    cut = start
    while item_at < len(items) or frame_at < len(frames):
        cut += BATCH_S
        first_frame, first_item = frame_at, item_at
        while frame_at < len(frames) and frames[frame_at].time < cut:
            frame_at += 1
        while item_at < len(items) and items[item_at].time < cut:
            item_at += 1
        batch = frames[first_frame:frame_at]
        if batch:
            sink.write_with(functools.partial(_write, batch=batch))
        pipeline.feed(items[first_item:item_at])
        pipeline.deliver()
    pipeline.finish()


def _write(channels: ChannelRegistry, batch: list[VideoFrame]) -> None:
    from analyzer.mcapio.write.video import write_frames

    write_frames(channels, batch)
