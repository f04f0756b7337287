"""Reading recordings back: raw items for re-decoding, events, metadata; damaged files too."""

from __future__ import annotations

import io
import json
import os
import struct
import zlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import IO, Any, Generic, TypeVar

from analyzer.errors import InputError
from analyzer.mcapio.channels import (
    RAW_TOPICS,
    ROLE_EVENT,
    ROLE_KEY,
    ROLE_RAW,
    ROLE_VIEW,
    TOPIC_CAN_FRAMES,
    TOPIC_STREAM_BYTES,
    can_frame_from_dict,
    stream_chunk_from_dict,
)
from analyzer.mcapio.chunks import (
    MAX_RECORD,
    MESSAGE_FIXED,
    OPCODE_CHUNK,
    OPCODE_DATA_END,
    OPCODE_MESSAGE,
    OPCODE_METADATA,
    RECORD_HEAD,
    ChunkDamage,
    chunk_payload,
    walk,
)
from analyzer.mcapio.foxglove import VIEW_SCHEMAS
from analyzer.mcapio.recover import Damage, Recovery, Scan, metadata_before_data, scan_records
from analyzer.pipeline import RawItem
from analyzer.protocol.types import (
    BAD_LINE,
    INCOMPLETE,
    LINK,
    TOPIC_DIAGNOSTICS,
    Event,
    diagnostic,
)

MAGIC = b"\x89MCAP0\r\n"
_MESSAGE_HEAD = struct.Struct("<HIQ")  # channel id, sequence, log time
FOOTER_RECORD_SIZE = 1 + 8 + 8 + 8 + 4  # opcode, length, summary start, offset start, crc
_FOOTER = struct.Struct("<BQQQI")
OPCODE_FOOTER = 0x02

T = TypeVar("T")
Tally = Callable[[str, str, int], None]

# Diagnostics that come from the source or the file reader, not from the decoder: decoding
# the raw channels again cannot re-create them, so a replay carries them over.
SOURCE_KINDS = frozenset({LINK, BAD_LINE})


class RecordingError(InputError):
    """The file is not an MCAP recording, or is damaged beyond its readable part (exit 2)."""


@dataclass(frozen=True, slots=True)
class RawMessage:
    """One message as stored: channel topic and role, log time (ns) and the JSON bytes."""

    topic: str
    role: str
    log_time: int
    data: bytes


def channel_role(topic: str, metadata: dict[str, str]) -> str:
    """Role of a channel: from its metadata, else guessed from the topic (other writers)."""
    role = metadata.get(ROLE_KEY)
    if role:
        return role
    if topic in RAW_TOPICS:
        return ROLE_RAW
    if topic in VIEW_SCHEMAS:
        return ROLE_VIEW
    return ROLE_EVENT


class Recording:
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
        self._summary_start = 0
        self._summary_crc = 0
        self._summary: Any = None
        try:
            self.size = os.path.getsize(self.path)
            with open(self.path, "rb") as f:
                head = f.read(len(MAGIC))
                damaged_magic = head != MAGIC and self._ends_with_magic(f)
                if head != MAGIC and not damaged_magic:
                    what = "an empty file" if not head else "not an MCAP file"
                    raise RecordingError(f"{self.path}: {what}")
                self.problem = self._check_end(f)
                if not self.problem:
                    self.problem = self._load_summary(f)
        except OSError as exc:
            raise RecordingError(f"cannot read {self.path}: {exc.strerror or exc}") from None
        self.recovered = bool(self.problem)
        self.summary_damaged = self.recovered and self._summary_start > 0
        self.recovery: Recovery | None = None
        # topic -> schema name of channels met by the recover path
        self.recovered_schemas: dict[str, str] = {}
        # parts of the file that reading skipped
        self.damage: list[Damage] = []
        if damaged_magic:
            self.damage.append(Damage(0, "the file's leading magic bytes are damaged"))
        self._damaged_chunks: set[int] = set()  # offsets of chunks already in ``damage``
        self._verified = False

    # -- opening ---------------------------------------------------------------------------------

    def _ends_with_magic(self, f: IO[bytes]) -> bool:
        if self.size < 2 * len(MAGIC) + FOOTER_RECORD_SIZE:
            return False
        f.seek(-len(MAGIC), os.SEEK_END)
        return f.read(len(MAGIC)) == MAGIC

    def _check_end(self, f: IO[bytes]) -> str:
        """'' when the file ends with a footer and magic, else what is missing."""
        if self.size < 2 * len(MAGIC) + FOOTER_RECORD_SIZE:
            return "the file has no footer (recording not finished)"
        f.seek(-len(MAGIC), os.SEEK_END)
        if f.read(len(MAGIC)) != MAGIC:
            return "the file has no footer (recording not finished)"
        f.seek(-(len(MAGIC) + FOOTER_RECORD_SIZE), os.SEEK_END)
        footer = f.read(FOOTER_RECORD_SIZE)
        opcode, length, start, _, crc = _FOOTER.unpack(footer)
        if opcode != OPCODE_FOOTER or length != 20:
            return "the file has no valid footer"
        footer_at = self.size - len(MAGIC) - FOOTER_RECORD_SIZE
        if start and not len(MAGIC) < start <= footer_at:
            self._summary_start = 0
            return "the footer points outside the file"
        self._summary_start, self._summary_crc = start, crc
        return ""

    def _load_summary(self, f: IO[bytes]) -> str:
        """Read and check the summary section; '' when it can be believed, else why not."""
        if not self._summary_start:
            self._summary = None
            return ""
        footer_at = self.size - len(MAGIC) - FOOTER_RECORD_SIZE
        f.seek(self._summary_start)
        section = f.read(footer_at - self._summary_start)
        f.seek(footer_at)
        footer = f.read(FOOTER_RECORD_SIZE)
        if self._summary_crc and zlib.crc32(footer[:-4], zlib.crc32(section)) != self._summary_crc:
            return (
                "the summary section fails its CRC check, so its statistics and index are not used"
            )
        try:
            self._summary = _parse_summary(section + footer + MAGIC)
        except Exception as exc:  # any parse failure of the summary means: read sequentially
            return f"the summary is unreadable ({_why(exc)})"
        return ""

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

    def summary(self) -> Any:
        """The mcap Summary of a finished file (None when recovered or written without one)."""
        return None if self.recovered else self._summary

    # -- metadata --------------------------------------------------------------------------------

    def metadata(self) -> dict[str, dict[str, str]]:
        """Metadata records by name. A recovered file gives the ones before its first chunk."""
        from mcap.data_stream import ReadDataStream
        from mcap.records import Metadata

        out: dict[str, dict[str, str]] = {}
        try:
            with open(self.path, "rb") as f:
                summary = self.summary()
                if summary is None:
                    return metadata_before_data(f, self.size)
                for index in summary.metadata_indexes:
                    if not 0 < index.offset <= index.offset + index.length <= self._data_end():
                        continue  # an index pointing outside the data: ignore it
                    f.seek(index.offset)
                    raw = f.read(index.length)
                    if len(raw) < 9 or raw[0] != OPCODE_METADATA:
                        continue
                    found = Metadata.read(ReadDataStream(io.BytesIO(raw[9:])))
                    out[found.name] = dict(found.metadata)
        except Exception:  # a damaged record ends the search; keep what was found
            pass
        return out

    def _data_end(self) -> int:
        return self._summary_start or self.size

    # -- messages --------------------------------------------------------------------------------

    def messages(
        self,
        topics: set[str] | None = None,
        roles: set[str] | None = None,
        *,
        tally: Tally | None = None,
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
        tally: Tally | None = None,
    ) -> Iterator[RawMessage | Damage]:
        """Like ``messages``, with a ``Damage`` entry where a part of the file was lost."""

        def wanted(topic: str, role: str) -> bool:
            return (topics is None or topic in topics) and (roles is None or role in roles)

        source = self._recover(wanted, tally) if self.recovered else self._read_finished(wanted)
        for entry in source:
            if isinstance(entry, Damage):
                self.damage.append(entry)
            yield entry

    def _unique_chunk_indexes(self) -> list[Any]:
        """The summary's chunk indexes, each chunk once, in file order."""
        seen: set[int] = set()
        out = []
        indexes = [] if self._summary is None else self._summary.chunk_indexes
        for index in sorted(indexes, key=lambda i: i.chunk_start_offset):
            if index.chunk_start_offset not in seen:
                seen.add(index.chunk_start_offset)
                out.append(index)
        return out

    def _read_finished(self, wanted: Callable[[str, str], bool]) -> Iterator[RawMessage | Damage]:
        """Through the summary's chunk index, reading only chunks that hold wanted channels."""
        summary = self._summary
        if summary is None or not summary.chunk_indexes:
            yield from self._read_with_library(wanted)
            return
        chosen = {
            channel_id: (ch.topic, channel_role(ch.topic, ch.metadata))
            for channel_id, ch in summary.channels.items()
            if wanted(ch.topic, channel_role(ch.topic, ch.metadata))
        }
        if not chosen:
            return
        indexes = [
            index
            for index in self._unique_chunk_indexes()
            if not index.message_index_offsets or chosen.keys() & index.message_index_offsets
        ]
        with open(self.path, "rb") as f:
            for index in indexes:
                try:
                    records = self._chunk_records(f, index)
                    found = [
                        RawMessage(*chosen[channel_id], log_time, data)
                        for channel_id, log_time, data in _messages_in(records)
                        if channel_id in chosen
                    ]
                except ChunkDamage as exc:  # skip it, keep reading, tell the caller
                    self._damaged_chunks.add(index.chunk_start_offset)
                    yield Damage(
                        index.message_start_time,
                        f"damaged chunk at byte {index.chunk_start_offset} skipped: {exc}",
                    )
                    continue
                yield from found

    def _chunk_records(self, f: IO[bytes], index: Any) -> bytes:
        """The records of the chunk an index entry points to (ChunkDamage when unusable)."""
        offset, length = index.chunk_start_offset, index.chunk_length
        if not len(MAGIC) <= offset < offset + length <= self._data_end() or length > MAX_RECORD:
            raise ChunkDamage("its index entry points outside the data section")
        f.seek(offset)
        raw = f.read(length)
        if len(raw) < 9 or raw[0] != OPCODE_CHUNK:
            raise ChunkDamage("no chunk where its index entry points")
        if RECORD_HEAD.unpack_from(raw)[1] != length - 9:
            raise ChunkDamage("its record length does not match its index entry")
        return chunk_payload(memoryview(raw)[9:])

    def verify(self) -> list[Damage]:
        """Check every chunk of a finished file (the data section CRC first: when it matches,
        nothing else is read). Returns the damaged parts not reported before, also added to
        ``damage``."""
        if self.recovered or self._summary is None or self._verified:
            return []
        self._verified = True
        found: list[Damage] = []
        with open(self.path, "rb") as f:
            stored = self._data_section_crc(f)
            if stored is not None and stored[0] and stored[0] == stored[1]:
                return []
            for index in self._unique_chunk_indexes():
                if index.chunk_start_offset in self._damaged_chunks:
                    continue
                try:
                    self._chunk_records(f, index)
                except ChunkDamage as exc:
                    self._damaged_chunks.add(index.chunk_start_offset)
                    found.append(
                        Damage(
                            index.message_start_time,
                            f"damaged chunk at byte {index.chunk_start_offset}: {exc}",
                        )
                    )
        if not found and not self._damaged_chunks and stored is not None and stored[0]:
            found.append(
                Damage(
                    0,
                    "the data section fails its CRC check outside the chunks (an index "
                    "or metadata record is damaged; the messages are intact)",
                )
            )
        self.damage.extend(found)
        return found

    def _data_section_crc(self, f: IO[bytes]) -> tuple[int, int] | None:
        """(stored, computed) CRC of the data section, None when there is no DataEnd."""
        end = self._summary_start - (9 + 4)
        if end < len(MAGIC):
            return None
        f.seek(end)
        record = f.read(13)
        opcode, length = RECORD_HEAD.unpack_from(record)
        if opcode != OPCODE_DATA_END or length != 4:
            return None
        stored = int.from_bytes(record[9:13], "little")
        crc, f_pos = 0, 0
        f.seek(0)
        while f_pos < end:
            block = f.read(min(1 << 20, end - f_pos))
            if not block:
                break
            crc = zlib.crc32(block, crc)
            f_pos += len(block)
        return stored, crc

    def _read_with_library(
        self, wanted: Callable[[str, str], bool]
    ) -> Iterator[RawMessage | Damage]:
        """Files without a chunk index (other writers): read sequentially."""
        summary = self._summary
        channels = {} if summary is None else dict(summary.channels)
        yield from self._scan(wanted, None, channels, Recovery(total_bytes=self.size))

    def _recover(
        self, wanted: Callable[[str, str], bool], tally: Tally | None
    ) -> Iterator[RawMessage | Damage]:
        report = Recovery(total_bytes=self.size)
        if self.summary_damaged:
            report.summary_problem = self.problem
        self.recovery = report
        yield from self._scan(wanted, tally, {}, report)

    def _scan(
        self,
        wanted: Callable[[str, str], bool],
        tally: Tally | None,
        channels: dict[int, Any],
        report: Recovery,
    ) -> Iterator[RawMessage | Damage]:
        scan = Scan(self.size, report, channels=channels)
        roles: dict[int, tuple[str, str, bool]] = {}  # channel id -> topic, role, wanted
        with open(self.path, "rb") as f:
            for entry in scan_records(f, scan):
                if isinstance(entry, Damage):
                    yield entry
                    continue
                known = roles.get(entry.channel_id)
                if known is None:
                    channel = scan.channels.get(entry.channel_id)
                    if channel is None:
                        report.unknown_channel += 1
                        continue
                    topic = channel.topic
                    role = channel_role(topic, dict(channel.metadata))
                    schema = scan.schemas.get(channel.schema_id)
                    self.recovered_schemas[topic] = schema.name if schema is not None else ""
                    known = roles[entry.channel_id] = (topic, role, wanted(topic, role))
                report.messages += 1
                if tally is not None:
                    tally(known[0], known[1], entry.log_time)
                if known[2]:
                    yield RawMessage(known[0], known[1], entry.log_time, entry.data)
        if report.unknown_channel and not any("definition" in d.detail for d in self.damage):
            yield Damage(
                0,
                f"{report.unknown_channel} messages skipped: the record defining their "
                "channel was lost",
            )

    # -- typed views -----------------------------------------------------------------------------

    def items(self) -> Iterator[RawItem]:
        """Raw CAN frames and stream chunks, for decoding again."""
        for message in self.messages(topics=set(RAW_TOPICS), roles={ROLE_RAW}):
            try:
                item = raw_item(message.topic, json.loads(message.data))
            except (ValueError, KeyError, TypeError):
                continue  # not one of ours: nothing to decode
            if item is not None:
                yield item

    def replay(self) -> Iterator[RawItem | Event]:
        """Raw items plus the stored diagnostics a decoder cannot re-create (link changes,
        unreadable input lines), in file order: what to feed a Decoder to decode again.
        A lost part of the file becomes an ``incomplete`` diagnostic where it was."""
        wanted = {*RAW_TOPICS, TOPIC_DIAGNOSTICS}
        last = 0
        for entry in self.entries(topics=wanted, roles={ROLE_RAW, ROLE_EVENT}):
            if isinstance(entry, Damage):
                yield self._damage_event(entry, last)
                continue
            last = entry.log_time
            try:
                obj = json.loads(entry.data)
                item = raw_item(entry.topic, obj)
                if item is not None:
                    yield item
                elif isinstance(obj, dict) and obj.get("kind") in SOURCE_KINDS:
                    obj.setdefault("topic", entry.topic)
                    obj.setdefault("time", entry.log_time / 1e9)
                    yield Event.from_dict(obj)
            except (ValueError, KeyError, TypeError):
                continue
        yield from self._unread_damage(last)

    def _unread_damage(self, last: int) -> Iterator[Event]:
        """Damaged chunks the read did not need (other channels): reported all the same."""
        for damage in self.verify():
            yield self._damage_event(damage, last)

    def events(self) -> Iterator[Event]:
        """The decoded events as recorded, with an ``incomplete`` diagnostic for a lost part."""
        last = 0
        for entry in self.entries(roles={ROLE_EVENT}):
            if isinstance(entry, Damage):
                yield self._damage_event(entry, last)
                continue
            last = entry.log_time
            try:
                obj = json.loads(entry.data)
                if not isinstance(obj, dict):
                    continue
                obj.setdefault("topic", entry.topic)
                obj.setdefault("time", entry.log_time / 1e9)
                yield Event.from_dict(obj)
            except (ValueError, KeyError, TypeError):
                continue
        yield from self._unread_damage(last)

    def _damage_event(self, damage: Damage, last: int) -> Event:
        when = (damage.log_time or last) / 1e9
        return diagnostic(when, self.path, INCOMPLETE, f"damaged recording: {damage.detail}")


def _parse_summary(section: bytes) -> Any:
    """The records of a summary section (already CRC-checked, followed by the footer and
    the closing magic) as an mcap Summary."""
    from mcap.records import (
        AttachmentIndex,
        Channel,
        ChunkIndex,
        MetadataIndex,
        Schema,
        Statistics,
    )
    from mcap.stream_reader import StreamReader
    from mcap.summary import Summary

    summary = Summary()
    reader = StreamReader(io.BytesIO(section), skip_magic=True, record_size_limit=len(section))
    for record in reader.records:
        if isinstance(record, Statistics):
            summary.statistics = record
        elif isinstance(record, Schema):
            summary.schemas[record.id] = record
        elif isinstance(record, Channel):
            summary.channels[record.id] = record
        elif isinstance(record, ChunkIndex):
            summary.chunk_indexes.append(record)
        elif isinstance(record, MetadataIndex):
            summary.metadata_indexes.append(record)
        elif isinstance(record, AttachmentIndex):
            summary.attachment_indexes.append(record)
    return summary


def _messages_in(records: bytes) -> Iterator[tuple[int, int, bytes]]:
    """(channel id, log time, data) of every message in a chunk's records."""
    unpack = _MESSAGE_HEAD.unpack_from
    for opcode, body, end in walk(records):
        if opcode == OPCODE_MESSAGE:
            if end - body < MESSAGE_FIXED:
                raise ChunkDamage("a message record is too short")
            channel_id, _, log_time = unpack(records, body)
            yield channel_id, log_time, records[body + MESSAGE_FIXED : end]


def _why(exc: BaseException) -> str:
    text = str(exc)
    name = type(exc).__name__
    if name == "EndOfFile" or not text:
        return "end of file inside a record (recording not finished)"
    return f"{name}: {text}"


class RecordingIterator(Generic[T]):
    """An iterator that also says whether its recording was recovered."""

    def __init__(self, recording: Recording, iterator: Iterator[T]) -> None:
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


def raw_item(topic: str, obj: Any) -> RawItem | None:
    """The frame or chunk of a raw-channel message (None for other topics)."""
    if topic == TOPIC_CAN_FRAMES:
        return can_frame_from_dict(obj)
    if topic == TOPIC_STREAM_BYTES:
        return stream_chunk_from_dict(obj)
    return None


def read_items(path: str | os.PathLike[str]) -> RecordingIterator[RawItem]:
    """Raw CAN frames / stream chunks of a recording, in arrival order (for re-decoding)."""
    recording = Recording(path)
    return RecordingIterator(recording, recording.items())


def read_replay(path: str | os.PathLike[str]) -> RecordingIterator[RawItem | Event]:
    """Raw items and the source-level diagnostics (link, bad_line) in arrival order."""
    recording = Recording(path)
    return RecordingIterator(recording, recording.replay())


def read_events(path: str | os.PathLike[str]) -> RecordingIterator[Event]:
    """The decoded events stored in a recording, in arrival order."""
    recording = Recording(path)
    return RecordingIterator(recording, recording.events())
