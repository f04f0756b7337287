"""Camera video in a recording: CompressedVideo and thumbnail channels, written and read."""

from __future__ import annotations

import base64
import json
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from analyzer.mcapio.channels import ROLE_KEY, time_ns
from analyzer.mcapio.chunked_writer import ChunkedWriter
from analyzer.mcapio.foxglove import TIME_SCHEMA
from analyzer.mcapio.writer import McapSink
from analyzer.pipeline import Batch
from analyzer.protocol.types import Event

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


def frame_id(name: str) -> str:
    return f"camera_{name}"


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


class VideoChannels:
    """Registers the camera channels on first use and writes frames and thumbnails."""

    def __init__(self) -> None:
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, int] = {}
        self._sequence: dict[int, int] = {}

    def write(self, writer: ChunkedWriter, frames: Sequence[VideoFrame]) -> None:
        for frame in frames:
            log_time = time_ns(frame.time)
            metadata = {
                ROLE_KEY: ROLE_VIDEO,
                "codec": frame.codec,
                "width": str(frame.width),
                "height": str(frame.height),
            }
            topic = video_topic(frame.stream)
            channel = self._channel(writer, topic, COMPRESSED_VIDEO_SCHEMA, metadata)
            data = message_json(frame.stream, frame.time, frame.data, frame.codec)
            writer.add_message(channel, log_time, data, log_time, self._next(channel))
            if frame.thumbnail is not None:
                topic = thumbnail_topic(frame.stream)
                meta = {ROLE_KEY: ROLE_THUMBNAIL}
                channel = self._channel(writer, topic, COMPRESSED_IMAGE_SCHEMA, meta)
                data = message_json(frame.stream, frame.time, frame.thumbnail, "jpeg")
                writer.add_message(channel, log_time, data, log_time, self._next(channel))

    def _next(self, channel: int) -> int:
        self._sequence[channel] += 1
        return self._sequence[channel]

    def _channel(
        self, writer: ChunkedWriter, topic: str, schema: dict[str, Any], metadata: dict[str, str]
    ) -> int:
        channel = self._channels.get(topic)
        if channel is not None:
            return channel
        name = str(schema["title"])
        schema_id = self._schemas.get(name)
        if schema_id is None:
            data = json.dumps(schema, separators=(",", ":")).encode()
            schema_id = self._schemas[name] = writer.register_schema(name, "jsonschema", data)
        channel = writer.register_channel(topic, "json", schema_id, metadata)
        self._channels[topic] = channel
        self._sequence[channel] = 0
        return channel


class VideoRecorder:
    """Sink writing what the camera streams delivered into the recording, batch by batch.

    Put it before the McapSink in the capture's sinks; its ``stage`` goes among the
    capture's stages and brings the streams' link diagnostics into the pipeline (so they
    reach /diagnostics, the status line and the counts like the telemetry's). The
    streams run in their own threads; ``stop`` ends them (also done by the stage's
    ``close`` at the end of the capture).
    """

    def __init__(self, mcap: McapSink, streams: Sequence[VideoStream]) -> None:
        self.mcap = mcap
        self.streams = list(streams)
        self.channels = VideoChannels()
        self.stage = _LinkStage(self)
        self.frames_written = 0
        self._frames: list[VideoFrame] = []

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
            events.extend(news)
        return events

    def handle(self, batch: Batch) -> None:
        frames, self._frames = self._frames, []
        if frames:
            frames.sort(key=lambda f: f.time)
            self.mcap.write_with(lambda writer: self.channels.write(writer, frames))
            self.frames_written += len(frames)

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
