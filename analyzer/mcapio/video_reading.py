"""Camera video of a recording read back: streams for `info`, thumbnails for `report`."""

from __future__ import annotations

import base64
import itertools
import json
import os
from collections.abc import Iterator
from dataclasses import asdict, dataclass, field
from typing import Any

from mcap.reader import McapReader

from analyzer import timefmt
from analyzer.mcapio.channels import ROLE_KEY
from analyzer.mcapio.video_channels import (
    COMPRESSED_IMAGE,
    COMPRESSED_VIDEO,
    ROLE_VIDEO,
    TOPIC_PREFIX,
)

GAP_FACTOR = 3.0  # frames further apart than this many frame intervals are a gap


@dataclass(slots=True)
class VideoSummary:
    """What ``info`` says of one camera stream in a recording."""

    topic: str
    codec: str = ""
    width: int = 0
    height: int = 0
    frames: int = 0
    thumbnails: int = 0
    first: float = 0.0
    last: float = 0.0
    gaps: list[tuple[float, float]] = field(default_factory=list)

    @property
    def fps(self) -> float:
        span = self.last - self.first
        return (self.frames - 1) / span if self.frames > 1 and span > 0 else 0.0


def _camera_topics(reader: McapReader) -> list[str] | None:
    """The camera channels' topics from the summary (None: no summary, read everything)."""
    try:
        summary = reader.get_summary()
    except Exception:  # an unfinished file: its messages are read in order instead
        return None
    if summary is None:
        return None
    names = (COMPRESSED_VIDEO, COMPRESSED_IMAGE)
    return [
        channel.topic
        for channel in summary.channels.values()
        if channel.schema_id in summary.schemas and summary.schemas[channel.schema_id].name in names
    ]


def video_summaries(path: str | os.PathLike[str]) -> list[VideoSummary]:
    """Every camera stream of a recording: codec, size, frames, rate and gaps."""
    from mcap.reader import make_reader

    out: dict[str, VideoSummary] = {}
    times: dict[str, list[float]] = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        topics = _camera_topics(reader)
        if topics == []:
            return []
        for schema, channel, message in reader.iter_messages(topics=topics):
            role = channel.metadata.get(ROLE_KEY, "")
            if schema is None or schema.name not in (COMPRESSED_VIDEO, COMPRESSED_IMAGE):
                continue
            if schema.name == COMPRESSED_IMAGE:
                base = channel.topic.removesuffix("/thumbnail")
                out.setdefault(base, VideoSummary(base)).thumbnails += 1
                continue
            summary = out.setdefault(channel.topic, VideoSummary(channel.topic))
            if role == ROLE_VIDEO and not summary.codec:
                summary.codec = channel.metadata.get("codec", "")
                summary.width = int(channel.metadata.get("width", "0") or 0)
                summary.height = int(channel.metadata.get("height", "0") or 0)
            summary.frames += 1
            times.setdefault(channel.topic, []).append(message.publish_time / 1e9)  # capture time
    for topic, stamps in times.items():
        stamps.sort()
        summary = out[topic]
        summary.first, summary.last = stamps[0], stamps[-1]
        if len(stamps) > 2:
            steps = sorted(b - a for a, b in itertools.pairwise(stamps))
            typical = steps[len(steps) // 2]
            summary.gaps = [
                (a, b)
                for a, b in itertools.pairwise(stamps)
                if typical > 0 and b - a > GAP_FACTOR * typical
            ]
    return [s for s in out.values() if s.frames or s.thumbnails]


@dataclass(frozen=True, slots=True)
class Thumbnail:
    """One JPEG of a camera stream at ``time`` (Unix seconds)."""

    stream: str
    time: float
    jpeg: bytes


def read_thumbnails(path: str | os.PathLike[str]) -> Iterator[Thumbnail]:
    """The thumbnails of every camera stream, in file order."""
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        reader = make_reader(f)
        topics = _camera_topics(reader)
        if topics == []:
            return
        for schema, channel, message in reader.iter_messages(topics=topics):
            if schema is None or schema.name != COMPRESSED_IMAGE:
                continue
            if not channel.topic.startswith(TOPIC_PREFIX):
                continue
            try:
                obj = json.loads(message.data)
                jpeg = base64.b64decode(obj["data"])
            except (ValueError, KeyError, TypeError):
                continue
            name = channel.topic[len(TOPIC_PREFIX) :].removesuffix("/thumbnail")
            yield Thumbnail(name, message.publish_time / 1e9, jpeg)


def video_lines(path: str | os.PathLike[str]) -> list[str]:
    """The ``info`` lines of the camera streams (none when the recording has no video)."""
    summaries = [s for s in video_summaries(path) if s.frames]
    if not summaries:
        return []
    width = max(len(s.topic) for s in summaries)
    lines = ["", "video streams (read from the file):"]
    for s in summaries:
        gaps = f"{len(s.gaps)} gaps" if len(s.gaps) != 1 else "1 gap"
        lines.append(
            f"  {s.topic:<{width}}  {s.codec} {s.width}x{s.height}  {s.fps:.1f} fps  "
            f"{s.frames} frames  {s.thumbnails} thumbnails  {gaps}"
        )
        for start, end in s.gaps[:5]:
            lines.append(
                f"  {'':<{width}}  gap {end - start:.2f} s from {timefmt.format_clock(start)}"
            )
    return lines


def video_dicts(path: str | os.PathLike[str]) -> list[dict[str, Any]]:
    """The same for ``info --json``."""
    return [{**asdict(s), "fps": round(s.fps, 3)} for s in video_summaries(path)]
