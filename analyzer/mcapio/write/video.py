"""Camera video in a recording: CompressedVideo, thumbnails and their overlays, written and read."""

from __future__ import annotations

import base64
import json
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

from analyzer.mcapio.channels import (
    ROLE_VIEW,
    ChannelSpec,
    channel_spec,
)
from analyzer.mcapio.foxglove import TIME_SCHEMA
from analyzer.mcapio.log_time import time_ns
from analyzer.mcapio.write.channel_registry import ChannelRegistry
from analyzer.mcapio.write.sink import McapSink
from analyzer.pipeline import Batch
from analyzer.protocol.types import Event
from analyzer.scene.scene3d import optical_frame

if TYPE_CHECKING:  # the streams import PyAV; reading a recording does not need it
    from analyzer.video.rtsp_stream import VideoFrame, VideoStream

ROLE_VIDEO = "video"
ROLE_THUMBNAIL = "thumbnail"
COMPRESSED_VIDEO = "foxglove.CompressedVideo"
COMPRESSED_IMAGE = "foxglove.CompressedImage"
TOPIC_PREFIX = "/camera/"
# Recording metadata key: the streams asked for, {name: URL without password}, so that
# `info` lists a stream that never delivered a frame.
VIDEO_METADATA_KEY = "video_streams"

# The fields of Foxglove's schemas (foxglove-sdk schemas/jsonschema), descriptions as there.
COMPRESSED_VIDEO_SCHEMA: dict[str, Any] = {
    "title": COMPRESSED_VIDEO,
    "description": "A single frame of a compressed video bitstream",
    "type": "object",
    "properties": {
        "timestamp": {**TIME_SCHEMA, "description": "Timestamp of video frame"},
        "frame_id": {
            "type": "string",
            "description": "Frame of reference for the video.\n\nThe origin of the frame is the "
            "optical center of the camera. +x points to the right in the video, +y points "
            "down, and +z points into the plane of the video.",
        },
        "data": {
            "type": "string",
            "contentEncoding": "base64",
            "description": "Compressed video frame data.\n\nFor packet-based video codecs this "
            "data must begin and end on packet boundaries (no partial packets), and must "
            "contain enough video packets to decode exactly one image (either a keyframe or "
            "delta frame). Note: Foxglove does not support video streams that include B "
            "frames because they require lookahead.",
        },
        "format": {
            "type": "string",
            "description": "Video format.\n\nSupported values: `h264`, `h265`, `vp9`, `av1`.",
        },
    },
    "required": ["timestamp", "frame_id", "data", "format"],
}

COMPRESSED_IMAGE_SCHEMA: dict[str, Any] = {
    "title": COMPRESSED_IMAGE,
    "description": "A compressed image",
    "type": "object",
    "properties": {
        "timestamp": {**TIME_SCHEMA, "description": "Timestamp of image"},
        "frame_id": {
            "type": "string",
            "description": "Frame of reference for the image. The origin of the frame is the "
            "optical center of the camera. +x points to the right in the image, +y points "
            "down, and +z points into the plane of the image.",
        },
        "data": {
            "type": "string",
            "contentEncoding": "base64",
            "description": "Compressed image data",
        },
        "format": {
            "type": "string",
            "description": "Image format\n\nSupported values: `jpeg`, `png`, `webp`, `avif`",
        },
    },
    "required": ["timestamp", "frame_id", "data", "format"],
}


def video_topic(name: str) -> str:
    return f"{TOPIC_PREFIX}{name}"


def thumbnail_topic(name: str) -> str:
    return f"{TOPIC_PREFIX}{name}/thumbnail"


def annotations_topic(name: str) -> str:
    """The overlays in the video's pixels (``foxglove.ImageAnnotations``)."""
    return f"{TOPIC_PREFIX}{name}/annotations"


def thumbnail_annotations_topic(name: str) -> str:
    """The overlays in the thumbnail's pixels."""
    return f"{TOPIC_PREFIX}{name}/thumbnail/annotations"


def frame_id(name: str) -> str:
    return optical_frame(name)


_SCHEMAS = {ROLE_VIDEO: COMPRESSED_VIDEO_SCHEMA, ROLE_THUMBNAIL: COMPRESSED_IMAGE_SCHEMA}


def _spec(topic: str, role: str) -> ChannelSpec:
    schema = _SCHEMAS[role]
    data = json.dumps(schema, separators=(",", ":")).encode()
    return ChannelSpec(topic, role, str(schema["title"]), data)


def camera_channel_specs(name: str) -> list[ChannelSpec]:
    """The channels of camera stream ``name``: video, thumbnails and their overlays (the
    live server advertises them before the first frame comes)."""
    return [
        _spec(video_topic(name), ROLE_VIDEO),
        _spec(thumbnail_topic(name), ROLE_THUMBNAIL),
        channel_spec(annotations_topic(name), ROLE_VIEW, {}),
        channel_spec(thumbnail_annotations_topic(name), ROLE_VIEW, {}),
    ]


def message_json(name: str, time: float, data: bytes, fmt: str) -> bytes:
    """One CompressedVideo / CompressedImage message (the two share their fields)."""
    ns = time_ns(time)
    message = {
        "timestamp": {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000},
        "frame_id": frame_id(name),
        "data": base64.b64encode(data).decode("ascii"),
        "format": fmt,
    }
    return json.dumps(message, separators=(",", ":")).encode()


def write_frames(channels: ChannelRegistry, frames: Sequence[VideoFrame]) -> None:
    """Camera frames (and their thumbnails) on their channels, registered at first use."""
    for frame in frames:
        log_time = time_ns(frame.time)
        metadata = {"codec": frame.codec, "width": str(frame.width), "height": str(frame.height)}
        channel = channels.register(_spec(video_topic(frame.stream), ROLE_VIDEO), metadata)
        data = message_json(frame.stream, frame.time, frame.data, frame.codec)
        channels.add_message(channel, log_time, data)
        if frame.thumbnail is not None:
            channel = channels.register(_spec(thumbnail_topic(frame.stream), ROLE_THUMBNAIL))
            data = message_json(frame.stream, frame.time, frame.thumbnail, "jpeg")
            channels.add_message(channel, log_time, data)


class VideoRecorder:
    """Sink writing what the camera streams delivered into the recording, batch by batch.

    Put it before the McapSink in the capture's sinks; its ``stage`` goes among the
    capture's stages and brings the streams' link diagnostics into the pipeline (so they
    reach /diagnostics, the status line and the counts like the telemetry's). The
    streams run in their own threads; ``stop`` ends them (also done by the stage's
    ``close`` at the end of the capture).
    """

    def __init__(
        self,
        mcap: McapSink,
        streams: Sequence[VideoStream],
        taps: Sequence[Callable[[list[VideoFrame]], None]] = (),
    ) -> None:
        self.mcap = mcap
        self.streams = list(streams)
        self.taps = list(taps)  # each gets the frames taken (a live judgement's pictures)
        self.stage = _LinkStage(self)
        self.frames_written = 0
        self._frames: list[VideoFrame] = []
        self._sizes: dict[str, tuple[int, int]] = {}  # the picture size the overlays are for
        for stream in self.streams:
            name = stream.spec.name
            mcap.add_camera(name)
            if mcap.tee is not None:
                for spec in camera_channel_specs(name):
                    mcap.tee.advertise(spec)

    def start(self) -> None:
        for stream in self.streams:
            stream.start()

    def stop(self) -> None:
        for stream in self.streams:
            stream.request_stop()
        for stream in self.streams:
            stream.stop()

    def collect(self) -> list[Event]:
        events: list[Event] = []
        for stream in self.streams:
            frames, news = stream.take()
            self._frames.extend(frames)
            for tap in self.taps:
                tap(frames)
            events.extend(news)
        return events

    def handle(self, batch: Batch) -> None:
        frames, self._frames = self._frames, []
        if frames:
            frames.sort(key=lambda f: f.time)
            self._size_overlays(frames)
            self.mcap.write_with(lambda channels: write_frames(channels, frames))
            self.frames_written += len(frames)

    def _size_overlays(self, frames: Sequence[VideoFrame]) -> None:
        """The overlays of a stream are drawn for its picture size, known from its frames
        (and changed with it, should the camera come back with another size)."""
        for frame in frames:
            size = (frame.width, frame.height)
            if self._sizes.get(frame.stream) == size or frame.width <= 0 or frame.height <= 0:
                continue
            from analyzer.video.thumbnail import thumbnail_size  # PyAV: video is recorded

            self._sizes[frame.stream] = size
            self.mcap.add_overlay(annotations_topic(frame.stream), *size)
            if any(s.thumbnail_interval > 0 for s in self.streams if s.spec.name == frame.stream):
                width, height = thumbnail_size(*size)
                topic = thumbnail_annotations_topic(frame.stream)
                # the thumbnails are what Foxglove Studio 1.48 shows: it draws lines, no text
                self.mcap.add_overlay(topic, width, height, stroked=True)

    def close(self) -> None:
        self.stop()

    def words(self) -> str:
        """The streams for the status line: "main 812 frames" / "main 401 unauthorized"."""
        parts = []
        for stream in self.streams:
            if stream.state == "connected" or not stream.state:
                parts.append(f"{stream.spec.name} {stream.frames} frames")
            elif stream.last_reason:
                parts.append(f"{stream.spec.name} {stream.last_reason.split(':')[0]}")
            else:
                parts.append(f"{stream.spec.name} {stream.state.replace('_', ' ')}")
        return "video: " + ", ".join(parts)


class _LinkStage:
    """The recorder's link diagnostics and queued frames, taken once per batch."""

    def __init__(self, recorder: VideoRecorder) -> None:
        self.recorder = recorder

    def process(self, events: list[Event]) -> list[Event]:
        return self.recorder.collect()

    def close(self) -> list[Event]:
        self.recorder.stop()
        return self.recorder.collect()
