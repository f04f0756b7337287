"""Reading recordings back: raw items for re-decoding, events, metadata; damaged files too."""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from typing import Any, Generic, TypeVar

from analyzer.mcapio.channels import (
    RAW_TOPICS,
    ROLE_EVENT,
    ROLE_RAW,
)
from analyzer.mcapio.read.file_end import RecordingError, read_file_end
from analyzer.mcapio.read.indexed import indexed_metadata, read_indexed, verify_chunks
from analyzer.mcapio.read.recover import Damage, Recovery, metadata_before_data
from analyzer.mcapio.read.ros_can import ROS_CAN_ROLES
from analyzer.mcapio.read.sequential import read_sequentially
from analyzer.mcapio.read.stored_message import (
    ChannelFilter,
    ChannelKind,
    MessageTally,
    RawMessage,
    ReadPosition,
    channel_kind,
    channel_role,
    raw_item,
    ros_item,
)
from analyzer.pipeline import RawItem
from analyzer.protocol.types import (
    BAD_LINE,
    INCOMPLETE,
    LINK,
    TOPIC_DIAGNOSTICS,
    CanFrame,
    Event,
    diagnostic,
)

__all__ = [
    "SOURCE_KINDS",
    "McapRecording",
    "RawMessage",
    "RecordingError",
    "RecordingIterator",
    "channel_role",
    "raw_item",
    "read_events",
    "read_items",
    "read_replay",
    "ros_item",
]

T = TypeVar("T")

# Diagnostics that come from the source or the file reader, not from the decoder: decoding
# the raw channels again cannot re-create them, so a replay carries them over.
SOURCE_KINDS = frozenset({LINK, BAD_LINE})


class McapRecording:
    """An MCAP file opened for reading.

    A finished file is read through its summary, once the summary passes its CRC check;
    every chunk read is decompressed within its declared size and checked against its CRC.
    A file without a valid footer / summary (the recorder was killed, the disk filled up,
    the summary is damaged) is read sequentially: ``recovered`` is True and, after a scan,
    ``recovery`` says how much was readable. Parts that cannot be read are skipped and
    listed in ``damage`` (and given to the typed views as ``Damage`` entries).
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = str(path)
        end = read_file_end(self.path)
        self.size = end.size
        self.problem = end.problem
        self._summary_start = end.summary_start
        self._summary: Any = end.summary
        self.recovered = bool(self.problem)
        self.summary_damaged = self.recovered and self._summary_start > 0
        self.recovery: Recovery | None = None
        # topic -> kind of the channels met by a sequential read
        self._kinds_seen: dict[str, ChannelKind] = {}
        # parts of the file that reading skipped
        self.damage: list[Damage] = []
        if end.damaged_magic:
            self.damage.append(Damage(0, "the file's leading magic bytes are damaged"))
        self._damaged_chunks: set[int] = set()  # offsets of chunks already in ``damage``
        self._verified = False
        self.position = ReadPosition()  # how far the current read has got, in bytes

    @property
    def recovery_note(self) -> str:
        """One line for the user when the file was recovered or damaged ('' otherwise)."""
        if not self.recovered:
            if not self.damage:
                return ""
            first = self.damage[0].detail
            return f"{len(self.damage)} damaged part(s) skipped; first: {first}"
        if self.recovery is None:
            return f"unfinished recording, read through the recover path: {self.problem}"
        return self.recovery.describe()

    @property
    def recovered_schemas(self) -> dict[str, str]:
        """Topic -> schema name of the channels met by the recover path."""
        return {topic: kind.schema for topic, kind in self._kinds_seen.items()}

    def channel_kinds(self) -> list[ChannelKind] | None:
        """The channels of the file, by topic: from the summary of a finished file; for a
        file read sequentially, those met so far (None before a read)."""
        summary = self.summary()
        if summary is not None and summary.channels:
            return sorted(
                (
                    channel_kind(
                        ch.topic,
                        dict(ch.metadata),
                        summary.schemas.get(ch.schema_id),
                        ch.message_encoding,
                    )
                    for ch in summary.channels.values()
                ),
                key=lambda kind: kind.topic,
            )
        if self._kinds_seen:
            return sorted(self._kinds_seen.values(), key=lambda kind: kind.topic)
        return None

    def summary(self) -> Any:
        """The mcap Summary of a finished file (None when recovered or written without one)."""
        return None if self.recovered else self._summary

    # -- metadata --------------------------------------------------------------------------------

    def metadata(self) -> dict[str, dict[str, str]]:
        """Metadata records by name. A recovered file gives the ones before its first chunk."""
        try:
            with open(self.path, "rb") as f:
                summary = self.summary()
                if summary is None:
                    return metadata_before_data(f, self.size)
                return indexed_metadata(f, summary, self._data_end())
        except Exception:  # a damaged record ends the search (found before it: kept there)
            return {}

    def _data_end(self) -> int:
        return self._summary_start or self.size

    # -- messages --------------------------------------------------------------------------------

    def messages(
        self,
        topics: set[str] | None = None,
        roles: set[str] | None = None,
        *,
        tally: MessageTally | None = None,
    ) -> Iterator[RawMessage]:
        """Messages in file order (= arrival order), filtered by topic and/or channel role.

        Recovered files only: ``tally(topic, role, log_time)`` is called for every message
        read, wanted or not, so one pass can count everything and yield only a few topics.
        Damaged parts are skipped and listed in ``damage``.
        """
        for entry in self.entries(topics, roles, tally=tally):
            if isinstance(entry, RawMessage):
                yield entry

    def entries(
        self,
        topics: set[str] | None = None,
        roles: set[str] | None = None,
        *,
        tally: MessageTally | None = None,
    ) -> Iterator[RawMessage | Damage]:
        """Like ``messages``, with a ``Damage`` entry where a part of the file was lost."""

        def wanted(topic: str, role: str) -> bool:
            return (topics is None or topic in topics) and (roles is None or role in roles)

        return self._entries_where(wanted, tally)

    def _entries_where(
        self, wanted: ChannelFilter, tally: MessageTally | None = None
    ) -> Iterator[RawMessage | Damage]:
        source = self._recover(wanted, tally) if self.recovered else self._read_finished(wanted)
        for entry in source:
            if isinstance(entry, Damage):
                self.damage.append(entry)
            yield entry

    def _read_finished(self, wanted: ChannelFilter) -> Iterator[RawMessage | Damage]:
        """Through the summary's chunk index, reading only chunks that hold wanted channels."""
        summary = self._summary
        if summary is None or not summary.chunk_indexes:
            yield from self._read_with_library(wanted)
            return
        roles = {
            channel_id: channel_role(
                ch.topic,
                ch.metadata,
                getattr(summary.schemas.get(ch.schema_id), "name", ""),
                ch.message_encoding,
            )
            for channel_id, ch in summary.channels.items()
        }
        chosen = {
            channel_id: (ch.topic, roles[channel_id])
            for channel_id, ch in summary.channels.items()
            if wanted(ch.topic, roles[channel_id])
        }
        if not chosen:
            return
        yield from read_indexed(
            self.path, summary, self._data_end(), chosen, self._damaged_chunks, self.position
        )

    def verify(self) -> list[Damage]:
        """Check every chunk of a finished file (the data section CRC first: when it matches,
        nothing else is read). Returns the damaged parts not reported before, also added to
        ``damage``."""
        if self.recovered or self._summary is None or self._verified:
            return []
        self._verified = True
        found = verify_chunks(
            self.path, self._summary, self._summary_start, self._data_end(), self._damaged_chunks
        )
        self.damage.extend(found)
        return found

    def _read_with_library(self, wanted: ChannelFilter) -> Iterator[RawMessage | Damage]:
        """Files without a chunk index (other writers): read sequentially."""
        summary = self._summary
        channels = {} if summary is None else dict(summary.channels)
        yield from self._scan(wanted, None, channels, Recovery(total_bytes=self.size))

    def _recover(
        self, wanted: ChannelFilter, tally: MessageTally | None
    ) -> Iterator[RawMessage | Damage]:
        report = Recovery(total_bytes=self.size)
        if self.summary_damaged:
            report.summary_problem = self.problem
        self.recovery = report
        yield from self._scan(wanted, tally, {}, report)

    def _scan(
        self,
        wanted: ChannelFilter,
        tally: MessageTally | None,
        channels: dict[int, Any],
        report: Recovery,
    ) -> Iterator[RawMessage | Damage]:
        return read_sequentially(
            self.path,
            self.size,
            wanted,
            tally,
            channels,
            report,
            kinds_seen=self._kinds_seen,
            damage=self.damage,
            position=self.position,
        )

    # -- typed views -----------------------------------------------------------------------------

    def items(self) -> Iterator[RawItem]:
        """Raw CAN frames and stream chunks, for decoding again (also the CAN frames of
        ROS bag channels; one that cannot be decoded is skipped: ``replay`` reports it)."""
        for entry in self._entries_where(_raw_or_ros):
            if not isinstance(entry, RawMessage):
                continue
            if entry.role in ROS_CAN_ROLES:
                frame = ros_item(entry)
                if isinstance(frame, CanFrame):
                    yield frame
                continue
            try:
                item = raw_item(entry.topic, json.loads(entry.data))
            except (ValueError, KeyError, TypeError):
                continue  # not one of ours: nothing to decode
            if item is not None:
                yield item

    def replay(self) -> Iterator[RawItem | Event]:
        """Raw items plus the stored diagnostics a decoder cannot re-create (link changes,
        unreadable input lines), in file order: what to feed a Decoder to decode again.
        A lost part of the file becomes an ``incomplete`` diagnostic where it was."""
        last = 0
        for entry in self._entries_where(_replayed):
            if isinstance(entry, Damage):
                yield self._damage_event(entry, last)
                continue
            last = entry.log_time
            if entry.role in ROS_CAN_ROLES:
                yield ros_item(entry)
                continue
            try:
                obj = json.loads(entry.data)
                item = raw_item(entry.topic, obj)
                if item is not None:
                    yield item
                elif isinstance(obj, dict) and obj.get("kind") in SOURCE_KINDS:
                    yield _stored_event(entry, obj)
            except (ValueError, KeyError, TypeError):
                continue
        yield from self._unread_damage(last)

    def _unread_damage(self, last: int) -> Iterator[Event]:
        """Damaged chunks the read did not need (other channels): reported all the same."""
        for damage in self.verify():
            yield self._damage_event(damage, last)

    def events(self, topics: set[str] | None = None) -> Iterator[Event]:
        """The decoded events as recorded, with an ``incomplete`` diagnostic for a lost part;
        with ``topics``, only the channels of those (a lost part only with /diagnostics)."""
        last = 0
        damage = topics is None or TOPIC_DIAGNOSTICS in topics
        for entry in self.entries(topics, roles={ROLE_EVENT}):
            if isinstance(entry, Damage):
                if damage:
                    yield self._damage_event(entry, last)
                continue
            last = entry.log_time
            try:
                obj = json.loads(entry.data)
                if isinstance(obj, dict):
                    yield _stored_event(entry, obj)
            except (ValueError, KeyError, TypeError):
                continue
        if damage:
            yield from self._unread_damage(last)

    def _damage_event(self, damage: Damage, last: int) -> Event:
        when = (damage.log_time or last) / 1e9
        return diagnostic(when, self.path, INCOMPLETE, f"damaged recording: {damage.detail}")


def _stored_event(entry: RawMessage, obj: dict[str, Any]) -> Event:
    """The event a message holds; one without a topic or time takes its channel's topic
    and its log time (ValueError / KeyError / TypeError when it is not an event)."""
    obj.setdefault("topic", entry.topic)
    obj.setdefault("time", entry.log_time / 1e9)
    return Event.from_dict(obj)


def _raw_or_ros(topic: str, role: str) -> bool:
    return (role == ROLE_RAW and topic in RAW_TOPICS) or role in ROS_CAN_ROLES


def _replayed(topic: str, role: str) -> bool:
    if role in ROS_CAN_ROLES:
        return True
    return topic in _REPLAYED_TOPICS and role in (ROLE_RAW, ROLE_EVENT)


_REPLAYED_TOPICS = frozenset({*RAW_TOPICS, TOPIC_DIAGNOSTICS})


class RecordingIterator(Generic[T]):
    """An iterator that also says whether its recording was recovered."""

    def __init__(self, recording: McapRecording, iterator: Iterator[T]) -> None:
        self.recording = recording
        self._iterator = iterator

    def __iter__(self) -> RecordingIterator[T]:
        return self

    def __next__(self) -> T:
        return next(self._iterator)

    @property
    def recovered(self) -> bool:
        return self.recording.recovered

    @property
    def damage(self) -> list[Damage]:
        """The parts of the file reading skipped so far."""
        return self.recording.damage

    @property
    def note(self) -> str:
        """'' for a finished file; else what the recover path read (complete after iterating)."""
        return self.recording.recovery_note


def read_items(path: str | os.PathLike[str]) -> RecordingIterator[RawItem]:
    """Raw CAN frames / stream chunks of a recording, in arrival order (for re-decoding)."""
    recording = McapRecording(path)
    return RecordingIterator(recording, recording.items())


def read_replay(path: str | os.PathLike[str]) -> RecordingIterator[RawItem | Event]:
    """Raw items and the source-level diagnostics (link, bad_line) in arrival order."""
    recording = McapRecording(path)
    return RecordingIterator(recording, recording.replay())


def read_events(path: str | os.PathLike[str]) -> RecordingIterator[Event]:
    """The decoded events stored in a recording, in arrival order."""
    recording = McapRecording(path)
    return RecordingIterator(recording, recording.events())
