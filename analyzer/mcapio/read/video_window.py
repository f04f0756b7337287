"""The camera video of a recording a time window at a time: only the chunks holding it are read."""

from __future__ import annotations

import base64
import os
from collections.abc import Iterator
from dataclasses import dataclass

import orjson

from analyzer.mcapio.read.indexed import chunk_records, messages_in, unique_chunk_indexes
from analyzer.mcapio.read.records import ChunkDamage
from analyzer.mcapio.read.stored_message import channel_role
from analyzer.mcapio.write.video import ROLE_VIDEO, TOPIC_PREFIX
from analyzer.video.annexb import is_key_slice, is_vcl

KEYFRAME_SEARCH_S = (2.0, 6.0, 20.0, 60.0)  # how far back a window looks for its keyframe


@dataclass(frozen=True, slots=True)
class StoredFrame:
    """One access unit of a camera stream: capture time, Annex B bytes, keyframe or not."""

    time: float
    data: bytes
    keyframe: bool
    codec: str


def starts_with_keyframe(codec: str, data: bytes) -> bool:
    """Whether an access unit holds a keyframe: its first picture slice is one (the NAL
    headers are read up to the first slice, not the whole unit)."""
    header = 2 if codec == "h265" else 1
    find = data.find
    position = find(b"\x00\x00\x01")
    while 0 <= position < len(data) - header - 3:
        byte = data[position + 3]
        kind = (byte >> 1) & 0x3F if codec == "h265" else byte & 0x1F
        if is_vcl(codec, kind):
            return is_key_slice(codec, kind)
        position = find(b"\x00\x00\x01", position + 3)
    return False


def parse_frame(message: bytes) -> StoredFrame | None:
    """A CompressedVideo message (JSON) as a frame; None for one that is not."""
    try:
        obj = orjson.loads(message)
        stamp = obj["timestamp"]
        when = int(stamp["sec"]) + int(stamp["nsec"]) / 1e9
        codec = str(obj.get("format", ""))
        data = base64.b64decode(obj["data"])
    except (ValueError, KeyError, TypeError):
        return None
    return StoredFrame(when, data, starts_with_keyframe(codec, data), codec)


class RecordedVideo:
    """The camera streams of a recording, read a window at a time.

    A finished recording is read through its chunk index: a window reads the chunks whose
    time range meets it (and, for the keyframe its first frame needs, those a little
    before). A recording without an index (cut short, recovered) is read from the start
    for each window. ``chunks_read`` counts the chunks read (for the benchmark)."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        from analyzer.mcapio.read.reader import McapRecording

        self.path = str(path)
        self.recording = McapRecording(path)
        self.chunks_read = 0
        summary = self.recording.summary()
        self._channels: dict[str, int] = {}
        self._indexes: list[object] = []
        if summary is not None and summary.chunk_indexes:
            self._indexes = unique_chunk_indexes(summary)
            for channel_id, channel in summary.channels.items():
                schema = getattr(summary.schemas.get(channel.schema_id), "name", "")
                role = channel_role(
                    channel.topic, dict(channel.metadata), schema, channel.message_encoding
                )
                if role == ROLE_VIDEO:
                    self._channels[channel.topic.removeprefix(TOPIC_PREFIX)] = channel_id
            self._data_end = self.recording._data_end()
        else:
            for kind in self.recording.channel_kinds() or ():
                if kind.role == ROLE_VIDEO:
                    self._channels[kind.topic.removeprefix(TOPIC_PREFIX)] = -1
            if not self._channels:  # not known before a read: look once
                for message in self.recording.messages(roles={ROLE_VIDEO}):
                    self._channels.setdefault(message.topic.removeprefix(TOPIC_PREFIX), -1)

    def streams(self) -> list[str]:
        """The names of the camera streams recorded (``main`` for /camera/main)."""
        return sorted(self._channels)

    def frames(self, stream: str, start: float, end: float) -> list[StoredFrame]:
        """The frames of ``stream`` from the keyframe at or before ``start`` to ``end``, in
        time order (empty when the stream has no frame there)."""
        if stream not in self._channels:
            return []
        for back in KEYFRAME_SEARCH_S:
            found = sorted(self._read(stream, start - back, end), key=lambda f: f.time)
            keys = [i for i, f in enumerate(found) if f.keyframe and f.time <= start]
            if keys:
                return found[keys[-1] :]
            if found and found[0].keyframe and found[0].time > start:
                break  # the stream starts after ``start``: from its first keyframe
        first_key = next((i for i, f in enumerate(found) if f.keyframe), None)
        return [] if first_key is None else found[first_key:]

    def _read(self, stream: str, start: float, end: float) -> Iterator[StoredFrame]:
        low, high = int(start * 1e9), int(end * 1e9)
        channel_id = self._channels[stream]
        if channel_id < 0 or not self._indexes:
            yield from self._scan(stream, low, high)
            return
        with open(self.path, "rb") as f:
            for index in self._indexes:
                offsets = getattr(index, "message_index_offsets", {})
                if offsets and channel_id not in offsets:
                    continue
                if index.message_end_time < low or index.message_start_time > high:  # type: ignore[attr-defined]
                    continue
                try:
                    records = chunk_records(f, index, self._data_end)
                    self.chunks_read += 1
                    for channel, log_time, data in messages_in(records):
                        if channel == channel_id and low <= log_time <= high:
                            frame = parse_frame(data)
                            if frame is not None:
                                yield frame
                except ChunkDamage:
                    continue  # a damaged chunk: its frames are a gap in the video

    def _scan(self, stream: str, low: int, high: int) -> Iterator[StoredFrame]:
        topic = TOPIC_PREFIX + stream
        for message in self.recording.messages(topics={topic}, roles={ROLE_VIDEO}):
            if low <= message.log_time <= high:
                frame = parse_frame(message.data)
                if frame is not None:
                    yield frame


def has_video(path: str | os.PathLike[str]) -> bool:
    """Whether a recording holds camera video (False for anything else, unreadable too)."""
    try:
        return bool(RecordedVideo(path).streams())
    except Exception:  # not a recording: no video to judge with
        return False
