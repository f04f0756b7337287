"""What a recording holds: time range, counts and rates per topic, and the run's figures."""

from __future__ import annotations

import json
import os
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from analyzer.mcapio.channels import METADATA_NAME, ROLE_EVENT, ROLE_RAW, STATS_METADATA_NAME
from analyzer.mcapio.read.file_end import read_header
from analyzer.mcapio.read.reader import McapRecording, RawMessage, channel_role, raw_item, ros_item
from analyzer.mcapio.read.ros_can import ROS_CAN_ROLES
from analyzer.pipeline import PipelineDecoder, default_decoder
from analyzer.protocol.types import Event
from analyzer.tally import Tally

SCANNED_ROLES = {ROLE_RAW, ROLE_EVENT, *ROS_CAN_ROLES}  # everything but the Foxglove views


@dataclass
class TopicInfo:
    topic: str
    role: str
    schema: str
    count: int
    rate_hz: float | None


@dataclass
class RecordingInfo:
    path: str
    size_bytes: int
    recovered: bool
    recovery_note: str
    start_ns: int | None
    end_ns: int | None
    message_count: int
    topics: list[TopicInfo]
    metadata: dict[str, str]
    tally: Tally  # the figures of the run that made the recording (analyzer.tally)
    # Where counts and stats came from: "summary", or which messages had to be scanned.
    counts_from: str
    stats_from: str
    scanned_messages: int = 0
    extra: dict[str, Any] = field(default_factory=dict)
    damage: list[str] = field(default_factory=list)  # parts of the file that cannot be read
    summary_damaged: bool = False  # a finished file whose summary failed its checks
    writer: str = ""  # the library and profile of the header record ("libmcap 1.4.1, profile ros2")
    # False for a live recording of this tool whose recorder never closed it (killed, power
    # lost): its provisional summary makes it complete up to the last flush, the closing stats
    # are absent. A finished file of another writer (a ROS bag) is closed.
    closed: bool = True

    @property
    def duration_s(self) -> float:
        if self.start_ns is None or self.end_ns is None:
            return 0.0
        return (self.end_ns - self.start_ns) / 1e9

    def to_dict(self) -> dict[str, Any]:
        return {
            "path": self.path,
            "size_bytes": self.size_bytes,
            "recovered": self.recovered,
            "recovery_note": self.recovery_note,
            "closed": self.closed,
            "start_time": None if self.start_ns is None else self.start_ns / 1e9,
            "end_time": None if self.end_ns is None else self.end_ns / 1e9,
            "duration_s": self.duration_s,
            "message_count": self.message_count,
            "topics": [vars(t) for t in self.topics],
            "metadata": self.metadata,
            # The figures decode --summary gives for the same input, under the same keys.
            "figures": self.tally.figures(),
            "diagnostics_by_kind": dict(sorted(self.tally.kinds.items())),
            "input": self.tally.items(),
            "counts_from": self.counts_from,
            "stats_from": self.stats_from,
            "scanned_messages": self.scanned_messages,
            "summary_damaged": self.summary_damaged,
            "writer": self.writer,
            "damage": self.damage,
        }


class _Fold:
    """Counts recorded messages into a tally: raw frames / chunks and events as recorded;
    the CAN frames of a ROS bag, which holds no decoded events, are decoded here."""

    def __init__(self, tally: Tally) -> None:
        self.tally = tally
        self.decoded = 0  # ROS frames decoded
        self._decoder: PipelineDecoder | None = None

    def __call__(self, message: RawMessage) -> None:
        if message.role in ROS_CAN_ROLES:
            frame = ros_item(message)
            if isinstance(frame, Event):
                self.tally.add_events((frame,))
                return
            self.tally.add_items((frame,))
            if self._decoder is None:
                self._decoder = default_decoder()
            self.tally.add_events(self._decoder.feed_can(frame))
            self.decoded += 1
            return
        _fold(self.tally, message)

    def finish(self) -> str:
        """Close the decoder; what the figures came from beyond the messages themselves."""
        if self._decoder is None:
            return ""
        self.tally.add_events(self._decoder.close())
        return f", the {self.decoded} CAN frames of ROS channels decoded again"


def _fold(tally: Tally, message: RawMessage) -> None:
    """Count one recorded message: a raw frame / chunk, or an event (as recorded)."""
    try:
        obj = json.loads(message.data)
    except ValueError:
        return
    if message.role == ROLE_RAW:
        try:
            item = raw_item(message.topic, obj)
        except (KeyError, TypeError, ValueError):
            return  # not one of ours
        if item is not None:
            tally.add_items((item,))
        return
    if not isinstance(obj, dict):
        return
    obj.setdefault("topic", message.topic)
    obj.setdefault("time", message.log_time / 1e9)
    try:
        tally.add_events((Event.from_dict(obj),))
    except (KeyError, TypeError, ValueError):
        return


def recording_info(path: str | os.PathLike[str], *, scan: bool = False) -> RecordingInfo:
    """Summarise a recording.

    A finished file is summarised from its MCAP summary (statistics, channels) and the stats
    record the writer adds at the end (the run's tally): no message is read. Without that
    record, or with ``scan``, the raw and event channels are read and counted again. A recovered
    (unfinished) file has no summary: its readable part is scanned once, sequentially.
    """
    recording = McapRecording(path)
    info = _summarise(recording, scan)
    profile, library = read_header(recording.path)
    info.writer = ", ".join(part for part in (library, profile and f"profile {profile}") if part)
    return info


def _summarise(recording: McapRecording, scan: bool) -> RecordingInfo:
    metadata = recording.metadata()
    base = dict(metadata.get(METADATA_NAME, {}))
    if recording.recovered:
        return _scan_everything(recording, base)
    summary = recording.summary()
    statistics = getattr(summary, "statistics", None)
    if summary is None or statistics is None:
        return _scan_everything(recording, base)
    damage = [d.detail for d in recording.verify()]
    topics = []
    counts = statistics.channel_message_counts
    duration = (statistics.message_end_time - statistics.message_start_time) / 1e9
    for channel in sorted(summary.channels.values(), key=lambda c: c.topic):
        count = int(counts.get(channel.id, 0))
        schema = summary.schemas.get(channel.schema_id)
        schema_name = schema.name if schema is not None else ""
        topics.append(
            TopicInfo(
                channel.topic,
                channel_role(
                    channel.topic, channel.metadata, schema_name, channel.message_encoding
                ),
                schema.name if schema is not None else "",
                count,
                count / duration if duration > 0 else None,
            )
        )
    empty = statistics.message_count == 0
    info = RecordingInfo(
        path=recording.path,
        size_bytes=recording.size,
        recovered=False,
        recovery_note="",
        start_ns=None if empty else statistics.message_start_time,
        end_ns=None if empty else statistics.message_end_time,
        message_count=statistics.message_count,
        topics=topics,
        metadata=base,
        tally=Tally(),
        counts_from="summary",
        stats_from="",
        damage=damage,
    )
    stored = metadata.get(STATS_METADATA_NAME)
    malformed = ""
    # Only this tool's own recordings end with the stats record: its absence there means
    # the recorder was killed; another writer's file with a footer and summary is finished.
    info.closed = stored is not None or METADATA_NAME not in metadata
    if stored is not None and not scan:
        try:
            info.tally = Tally.from_metadata(stored)
            info.stats_from = "the stats record written at the end, no scan"
            return info
        except (ValueError, KeyError, TypeError, AttributeError, OverflowError):
            malformed = " (the stats record written at the end is malformed)"
    tally = Tally()
    fold = _Fold(tally)
    scanned = 0
    for message in recording.messages(roles=SCANNED_ROLES):
        scanned += 1
        fold(message)
    decoded = fold.finish()
    info.tally = tally
    info.scanned_messages = scanned
    info.stats_from = (
        f"a scan of the recorded frames and events, {scanned} messages{decoded}{malformed}"
    )
    info.damage = [d.detail for d in recording.damage]
    return info


def _scan_everything(recording: McapRecording, base: dict[str, str]) -> RecordingInfo:
    counts: Counter[str] = Counter()
    roles: dict[str, str] = {}
    times: dict[str, list[int]] = {}  # topic -> [first, last] log time

    def tally(topic: str, role: str, log_time: int) -> None:
        counts[topic] += 1
        span = times.get(topic)
        if span is None:
            times[topic] = [log_time, log_time]
            roles[topic] = role
        elif log_time < span[0]:
            span[0] = log_time
        elif log_time > span[1]:
            span[1] = log_time

    figures = Tally()
    fold = _Fold(figures)
    if recording.recovered:
        messages = recording.messages(roles=SCANNED_ROLES, tally=tally)
    else:  # a finished file without statistics: count while reading everything
        messages = (
            m for m in recording.messages() if _tallied(tally, m) and m.role in SCANNED_ROLES
        )
    for message in messages:
        fold(message)
    decoded = fold.finish()
    scanned = sum(counts.values())
    start = min((span[0] for span in times.values()), default=None)
    end = max((span[1] for span in times.values()), default=None)
    duration = 0.0 if start is None or end is None else (end - start) / 1e9
    topics = [
        TopicInfo(
            topic,
            roles[topic],
            recording.recovered_schemas.get(topic, ""),
            n,
            n / duration if duration > 0 else None,
        )
        for topic, n in sorted(counts.items())
    ]
    why = "recovered file" if recording.recovered else "the file has no summary statistics"
    return RecordingInfo(
        path=recording.path,
        size_bytes=recording.size,
        recovered=recording.recovered,
        recovery_note=recording.recovery_note,
        start_ns=start,
        end_ns=end,
        message_count=scanned,
        topics=topics,
        metadata=base,
        tally=figures,
        counts_from=f"a full sequential scan: {why}",
        stats_from=f"the same scan: {why}{decoded}",
        scanned_messages=scanned,
        damage=[d.detail for d in recording.damage],
        summary_damaged=recording.summary_damaged,
    )


def _tallied(tally: Callable[[str, str, int], None], message: RawMessage) -> bool:
    tally(message.topic, message.role, message.log_time)
    return True
