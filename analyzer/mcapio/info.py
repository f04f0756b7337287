"""Summary of a recording: time range, counts and rates per topic, diagnostics, feedback gaps."""

from __future__ import annotations

import json
import os
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from analyzer.feedback_track import GAP_THRESHOLD_S
from analyzer.mcapio.channels import METADATA_NAME, STATS_METADATA_NAME
from analyzer.mcapio.reader import RawMessage, Recording, channel_role
from analyzer.mcapio.stats import EventStats
from analyzer.protocol.types import TOPIC_DIAGNOSTICS, TOPIC_GIMBAL_ATTITUDE

SCANNED_TOPICS = (TOPIC_DIAGNOSTICS, TOPIC_GIMBAL_ATTITUDE)


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
    stats: EventStats
    # Where counts and stats came from: "summary", or which messages had to be scanned.
    counts_from: str
    stats_from: str
    scanned_messages: int = 0
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def duration_s(self) -> float:
        if self.start_ns is None or self.end_ns is None:
            return 0.0
        return (self.end_ns - self.start_ns) / 1e9

    def to_dict(self) -> dict[str, Any]:
        stats = self.stats
        return {
            "path": self.path,
            "size_bytes": self.size_bytes,
            "recovered": self.recovered,
            "recovery_note": self.recovery_note,
            "start_time": None if self.start_ns is None else self.start_ns / 1e9,
            "end_time": None if self.end_ns is None else self.end_ns / 1e9,
            "duration_s": self.duration_s,
            "message_count": self.message_count,
            "topics": [vars(t) for t in self.topics],
            "metadata": self.metadata,
            "diagnostics_by_kind": dict(sorted(stats.diagnostics.items())),
            "feedback": {
                "attitude_count": stats.attitude_count,
                "max_gap_s": stats.max_gap_s if stats.attitude_count > 1 else None,
                "max_gap_at": stats.max_gap_at,
                "gap_threshold_s": GAP_THRESHOLD_S,
                "gaps_over_threshold": stats.gaps_over_threshold,
            },
            "counts_from": self.counts_from,
            "stats_from": self.stats_from,
            "scanned_messages": self.scanned_messages,
        }


def _kind(data: bytes) -> str:
    try:
        obj = json.loads(data)
        return str(obj.get("kind", "unknown")) if isinstance(obj, dict) else "unknown"
    except ValueError:
        return "unknown"


def recording_info(path: str | os.PathLike[str], *, scan: bool = False) -> RecordingInfo:
    """Summarise a recording.

    A finished file is summarised from its MCAP summary (statistics, channels) and the stats
    record the writer adds at the end: no message is read. Without that record, or with
    ``scan``, only the /diagnostics and /gimbal/attitude channels are scanned. A recovered
    (unfinished) file has no summary: its readable part is scanned once, sequentially.
    """
    recording = Recording(path)
    metadata = recording.metadata()
    base = dict(metadata.get(METADATA_NAME, {}))
    if recording.recovered:
        return _scan_everything(recording, base)
    summary = recording.summary()
    statistics = getattr(summary, "statistics", None)
    if summary is None or statistics is None:
        return _scan_everything(recording, base)
    topics = []
    counts = statistics.channel_message_counts
    duration = (statistics.message_end_time - statistics.message_start_time) / 1e9
    for channel in sorted(summary.channels.values(), key=lambda c: c.topic):
        count = int(counts.get(channel.id, 0))
        schema = summary.schemas.get(channel.schema_id)
        topics.append(
            TopicInfo(
                channel.topic,
                channel_role(channel.topic, channel.metadata),
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
        stats=EventStats(),
        counts_from="summary",
        stats_from="",
    )
    stored = metadata.get(STATS_METADATA_NAME)
    if stored is not None and not scan:
        try:
            info.stats = EventStats.from_metadata(stored)
            info.stats_from = "the stats record written at the end, no scan"
            return info
        except (ValueError, KeyError, TypeError):
            pass
    stats = EventStats()
    scanned = 0
    for message in recording.messages(topics=set(SCANNED_TOPICS)):
        scanned += 1
        if message.topic == TOPIC_DIAGNOSTICS:
            stats.diagnostics[_kind(message.data)] += 1
        else:
            stats.feedback.add(message.log_time / 1e9)
    info.stats = stats
    info.scanned_messages = scanned
    info.stats_from = f"a scan of {' and '.join(SCANNED_TOPICS)} only, {scanned} messages"
    return info


def _scan_everything(recording: Recording, base: dict[str, str]) -> RecordingInfo:
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

    stats = EventStats()
    content = set(SCANNED_TOPICS)
    if recording.recovered:
        messages = recording.messages(topics=content, tally=tally)
    else:  # a finished file without statistics: count while reading everything
        messages = (m for m in recording.messages() if _tallied(tally, m) and m.topic in content)
    for message in messages:
        if message.topic == TOPIC_DIAGNOSTICS:
            stats.diagnostics[_kind(message.data)] += 1
        else:
            stats.feedback.add(message.log_time / 1e9)
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
        stats=stats,
        counts_from=f"a full sequential scan: {why}",
        stats_from=f"the same scan: {why}",
        scanned_messages=scanned,
    )


def _tallied(tally: Callable[[str, str, int], None], message: RawMessage) -> bool:
    tally(message.topic, message.role, message.log_time)
    return True
