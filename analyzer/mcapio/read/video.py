"""Camera video of a recording read back: streams for `info`, thumbnails for `report`."""

from __future__ import annotations

import base64
import itertools
import json
import os
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, field
from typing import Any

from analyzer import timefmt
from analyzer.extras import VIDEO, installed, not_installed_note
from analyzer.mcapio.write.video import (
    ROLE_THUMBNAIL,
    ROLE_VIDEO,
    TOPIC_PREFIX,
    VIDEO_METADATA_KEY,
)

GAP_FACTOR = 3.0  # frames further apart than this many frame intervals are a gap


@dataclass(frozen=True, slots=True)
class _Message:
    """A camera message: topic, channel role, capture time, format and decoded data."""

    topic: str
    role: str
    time: float
    format: str
    data: bytes


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
    requested: str = ""  # the URL (without password) the recorder was asked to record
    failed: bool = False  # asked for, and not one frame recorded

    @property
    def fps(self) -> float:
        """Frames per second while the stream was connected (a gap is an outage, not a
        slow stream)."""
        span = self.last - self.first - sum(end - start for start, end in self.gaps)
        intervals = self.frames - 1 - len(self.gaps)
        return intervals / span if intervals > 0 and span > 0 else 0.0


def _camera_messages(
    path: str | os.PathLike[str],
    roles: set[str],
    *,
    decode: bool = True,
    read: Callable[[int], None] | None = None,
) -> Iterator[_Message]:
    """The camera messages of a recording with their JSON, through the project's reader (a
    recording cut short by a full disk or ``kill -9`` is recovered like for every command).
    Without ``decode`` their data is left out (empty). ``read`` is told how many bytes of
    the file the read has got through, with each message (for a progress line)."""
    from analyzer.mcapio.read.reader import McapRecording

    recording = McapRecording(path)
    for message in recording.messages(roles=roles):
        if read is not None:
            read(recording.position.bytes)
        try:
            obj = json.loads(message.data)
            stamp = obj["timestamp"]
            when = int(stamp["sec"]) + int(stamp["nsec"]) / 1e9
            data = base64.b64decode(obj["data"]) if decode else b""
        except (ValueError, KeyError, TypeError):
            continue  # not a message of ours: nothing to show
        yield _Message(message.topic, message.role, when, str(obj.get("format", "")), data)


def video_summaries(path: str | os.PathLike[str]) -> list[VideoSummary]:
    """Every camera stream of a recording: codec, size, frames, rate and gaps (the size
    only with the video extra, which decodes a picture)."""
    size_of: Callable[[str, bytes], tuple[int, int]] | None = None
    if installed(VIDEO):
        from analyzer.video.thumbnail import picture_size as size_of

    out: dict[str, VideoSummary] = {}
    times: dict[str, list[float]] = {}
    for message in _camera_messages(path, {ROLE_VIDEO, ROLE_THUMBNAIL}):
        if message.role == ROLE_THUMBNAIL:
            base = message.topic.removesuffix("/thumbnail")
            out.setdefault(base, VideoSummary(base)).thumbnails += 1
            continue
        summary = out.setdefault(message.topic, VideoSummary(message.topic))
        if not summary.codec:
            summary.codec = message.format
        if not summary.width and size_of is not None:  # the first picture that decodes
            summary.width, summary.height = size_of(message.format, message.data)
        summary.frames += 1
        times.setdefault(message.topic, []).append(message.time)
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
    shown = [s for s in out.values() if s.frames or s.thumbnails]
    for name, url in requested_streams(path).items():
        topic = TOPIC_PREFIX + name
        summary = out.get(topic) or VideoSummary(topic)
        if summary not in shown:
            shown.append(summary)
        summary.requested = url
        summary.failed = not summary.frames
    return shown


def requested_streams(path: str | os.PathLike[str]) -> dict[str, str]:
    """The streams the recorder was asked for, {name: URL}, from the recording's
    metadata (empty for recordings made before it was written down)."""
    from analyzer.mcapio.channels import METADATA_NAME
    from analyzer.mcapio.read.reader import McapRecording

    text = McapRecording(path).metadata().get(METADATA_NAME, {}).get(VIDEO_METADATA_KEY)
    try:
        found = json.loads(text) if text else {}
    except ValueError:
        return {}
    if not isinstance(found, dict):
        return {}
    return {str(name): str(url) for name, url in found.items()}


@dataclass(frozen=True, slots=True)
class Thumbnail:
    """One JPEG of a camera stream at ``time`` (Unix seconds)."""

    stream: str
    time: float
    jpeg: bytes


def read_thumbnails(
    path: str | os.PathLike[str], read: Callable[[int], None] | None = None
) -> Iterator[Thumbnail]:
    """The thumbnails of every camera stream, in file order (times: capture times);
    ``read`` as for ``thumbnail_times``."""
    for message in _camera_messages(path, {ROLE_THUMBNAIL}, read=read):
        name = message.topic.removeprefix(TOPIC_PREFIX).removesuffix("/thumbnail")
        yield Thumbnail(name, message.time, message.data)


def thumbnail_times(
    path: str | os.PathLike[str], read: Callable[[int], None] | None = None
) -> list[float]:
    """The times of every camera stream's thumbnails (those ``read_thumbnails`` gives);
    ``read`` is told how many bytes of the file were read, with each thumbnail."""
    messages = _camera_messages(path, {ROLE_THUMBNAIL}, decode=False, read=read)
    return [message.time for message in messages]


def video_lines(path: str | os.PathLike[str], zone: timefmt.TimeZone = timefmt.UTC) -> list[str]:
    """The ``info`` lines of the camera streams (none when the recording has no video),
    the gaps' times in ``zone``."""
    summaries = [s for s in video_summaries(path) if s.frames or s.failed]
    if not summaries:
        return []
    width = max(len(s.topic) for s in summaries)
    lines = ["", "video streams (read from the file):"]
    for s in summaries:
        if s.failed:
            lines.append(
                f"  {s.topic:<{width}}  requested ({s.requested}), failed: no frame recorded"
            )
            continue
        gaps = f"{len(s.gaps)} gaps" if len(s.gaps) != 1 else "1 gap"
        size = f"{s.width}x{s.height}" if s.width else "size not read"
        lines.append(
            f"  {s.topic:<{width}}  {s.codec} {size}  {s.fps:.1f} fps  "
            f"{s.frames} frames  {s.thumbnails} thumbnails  {gaps}"
        )
        for start, end in s.gaps[:5]:
            lines.append(
                f"  {'':<{width}}  gap {end - start:.2f} s from {zone.format_clock(start)}"
            )
    missing = not_installed_note(VIDEO, "picture sizes not read")
    if missing is not None:
        lines.append(f"  note: {missing}")
    return lines


def video_dicts(path: str | os.PathLike[str]) -> list[dict[str, Any]]:
    """The same for ``info --json``."""
    return [{**asdict(s), "fps": round(s.fps, 3)} for s in video_summaries(path)]
