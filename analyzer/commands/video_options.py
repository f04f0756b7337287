"""The video part of a recording command: streams from the options, attached to the capture."""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from typing import TYPE_CHECKING

from analyzer.mcapio.write.video import VIDEO_METADATA_KEY
from analyzer.video.spec import DEFAULT_THUMBNAIL_S, VideoSpec, is_simulated, video_specs

if TYPE_CHECKING:
    from analyzer.mcapio.write.sink import McapSink
    from analyzer.mcapio.write.video import VideoRecorder
    from analyzer.video.rtsp_stream import VideoStream

# A stream of the simulated camera (given its spec and thumbnail interval): demo's.
SimulatedStreams = Callable[[VideoSpec, float], "VideoStream"]


def video_metadata(args: argparse.Namespace) -> dict[str, str]:
    """The recording metadata of the ``--video`` streams asked for (empty without)."""
    specs = video_specs(args)
    if not specs:
        return {}
    return {VIDEO_METADATA_KEY: json.dumps({spec.name: spec.shown for spec in specs})}


def video_recorder(
    args: argparse.Namespace, mcap: McapSink, simulated: SimulatedStreams | None = None
) -> VideoRecorder | None:
    """The recorder of the ``--video`` streams into ``mcap`` (None without ``--video``);
    ``simulated`` makes the streams of ``--camera sim``.

    Put ``recorder`` first among the capture's sinks and ``recorder.stage`` among its
    stages; ``recorder.start()`` when the capture starts, ``recorder.stop()`` at the end."""
    specs = video_specs(args)
    if not specs:
        return None
    from analyzer.mcapio.write.video import VideoRecorder
    from analyzer.video.rtsp_stream import VideoStream

    interval = getattr(args, "thumbnail_interval", DEFAULT_THUMBNAIL_S)
    streams = [
        simulated(spec, interval or 0.0)
        if simulated is not None and is_simulated(spec)
        else VideoStream(spec, thumbnail_interval=interval or 0.0)
        for spec in specs
    ]
    return VideoRecorder(mcap, streams)


def video_summary(recorder: VideoRecorder) -> str:
    """The last word on the video: frames per stream, drops, and the stream's last problem."""
    parts = []
    for stream in recorder.streams:
        words = f"/camera/{stream.spec.name}: {stream.frames} frames"
        if stream.dropped:
            words += f" ({stream.dropped} dropped)"
        if not stream.frames and stream.last_problem:
            words += f" (last link message: {stream.last_problem})"
        parts.append(words)
    return "video " + "; ".join(parts)


def video_frames(recorder: VideoRecorder) -> str | None:
    """What the streams recorded, in words ("147 video frames of /camera/main"); None
    when no stream delivered a frame."""
    parts = [f"/camera/{s.spec.name}" for s in recorder.streams if s.frames]
    total = sum(s.frames for s in recorder.streams)
    return f"{total} video frame(s) of {', '.join(parts)}" if total else None


def silent_streams(recorder: VideoRecorder) -> list[str]:
    """A sentence for each stream asked for that delivered no frame at all."""
    out = []
    for stream in recorder.streams:
        if stream.frames:
            continue
        words = (
            f"the video stream /camera/{stream.spec.name} ({stream.spec.shown}) delivered no frame"
        )
        if stream.last_problem:
            words += f" (last link message: {stream.last_problem})"
        out.append(words)
    return out
