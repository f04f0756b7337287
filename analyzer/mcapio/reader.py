"""Reading recordings back: raw items for re-decoding, events, metadata; recovers crashed files."""

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
from analyzer.mcapio.foxglove import VIEW_SCHEMAS
from analyzer.pipeline import RawItem
from analyzer.protocol.types import BAD_LINE, LINK, TOPIC_DIAGNOSTICS, Event

MAGIC = b"\x89MCAP0\r\n"
OPCODE_SCHEMA = 0x03
OPCODE_CHANNEL = 0x04
OPCODE_MESSAGE = 0x05
OPCODE_CHUNK = 0x06
_RECORD_HEAD = struct.Struct("<BQ")
_MESSAGE_HEAD = struct.Struct("<HIQ")  # channel id, sequence, log time
FOOTER_RECORD_SIZE = 1 + 8 + 8 + 8 + 4  # opcode, length, summary start, offset start, crc
OPCODE_FOOTER = 0x02
# A record longer than this in a damaged tail is garbage, not data.
RECORD_SIZE_LIMIT = 1 << 30

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


@dataclass
class Recovery:
    """What the recover path of a crashed (unfinished) file could read."""

    messages: int = 0
    good_bytes: int = 0  # bytes up to the end of the last complete record
    total_bytes: int = 0
    damaged_chunks: int = 0
    data_complete: bool = False  # the data section ended properly; only the summary is bad
    reason: str = ""

    def describe(self) -> str:
        lost = self.total_bytes - self.good_bytes
        text = (
            f"recovered {self.messages} messages from an unfinished recording "
            f"({self.good_bytes} of {self.total_bytes} bytes readable"
        )
        if lost > 0 and not self.data_complete:
            text += f", {lost} bytes of unfinished data at the end"
        text += ")"
        if self.damaged_chunks:
            text += f"; {self.damaged_chunks} damaged chunk(s) skipped"
        if self.reason:
            text += f"; {self.reason}"
        return text


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

    A finished file is read through its summary with CRC validation. A file without a
    valid footer/summary (the recorder was killed, the disk filled up) is *recovered*:
    its data section is read sequentially up to the last complete chunk; ``recovered`` is
    True and, after a scan, ``recovery`` says how much was readable.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = str(path)
        try:
            self.size = os.path.getsize(self.path)
            with open(self.path, "rb") as f:
                head = f.read(len(MAGIC))
                if head != MAGIC:
                    what = "an empty file" if not head else "not an MCAP file"
                    raise RecordingError(f"{self.path}: {what}")
                self.problem = self._check_end(f)
        except OSError as exc:
            raise RecordingError(f"cannot read {self.path}: {exc.strerror or exc}") from None
        self.recovered = bool(self.problem)
        self.recovery: Recovery | None = None
        self._summary: Any = None
        # topic -> schema name of channels met by the recover path
        self.recovered_schemas: dict[str, str] = {}
        # damaged chunks of a finished file that reading skipped
        self.damage: list[str] = []
        if not self.recovered:
            self._load_summary()

    # -- opening ---------------------------------------------------------------------------------

    def _check_end(self, f: IO[bytes]) -> str:
        """'' when the file ends with a footer and magic, else what is missing."""
        if self.size < 2 * len(MAGIC) + FOOTER_RECORD_SIZE:
            return "the file has no footer (recording not finished)"
        f.seek(-len(MAGIC), os.SEEK_END)
        if f.read(len(MAGIC)) != MAGIC:
            return "the file has no footer (recording not finished)"
        f.seek(-(len(MAGIC) + FOOTER_RECORD_SIZE), os.SEEK_END)
        footer = f.read(FOOTER_RECORD_SIZE)
        if footer[0] != OPCODE_FOOTER or struct.unpack_from("<Q", footer, 1)[0] != 20:
            return "the file has no valid footer"
        return ""

    def _load_summary(self) -> None:
        from mcap.reader import make_reader

        try:
            with open(self.path, "rb") as f:
                self._summary = make_reader(f, validate_crcs=True).get_summary()
        except Exception as exc:  # any parse failure of the summary means: recover
            self.problem = f"the summary is unreadable ({exc})"
            self.recovered = True
            self._summary = None

    @property
    def recovery_note(self) -> str:
        """One line for the user when the file was recovered or damaged ('' otherwise)."""
        if not self.recovered:
            if not self.damage:
                return ""
            return f"{len(self.damage)} damaged chunk(s) skipped; first: {self.damage[0]}"
        if self.recovery is None:
            return f"unfinished recording, read through the recover path: {self.problem}"
        return self.recovery.describe()

    def summary(self) -> Any:
        """The mcap Summary of a finished file (None when recovered or written without one)."""
        return self._summary

    # -- metadata --------------------------------------------------------------------------------

    def metadata(self) -> dict[str, dict[str, str]]:
        """Metadata records by name. A recovered file gives the ones before its first chunk."""
        from mcap.records import Chunk, Metadata
        from mcap.stream_reader import StreamReader

        out: dict[str, dict[str, str]] = {}
        try:
            with open(self.path, "rb") as f:
                if not self.recovered:
                    from mcap.reader import make_reader

                    for found in make_reader(f).iter_metadata():
                        out[found.name] = dict(found.metadata)
                    return out
                reader = StreamReader(f, emit_chunks=True, record_size_limit=RECORD_SIZE_LIMIT)
                for record in reader.records:
                    if isinstance(record, Metadata):
                        out[record.name] = dict(record.metadata)
                    elif isinstance(record, Chunk):
                        break
        except Exception:  # a damaged tail ends the search; keep what was found
            pass
        return out

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
        """

        def wanted(topic: str, role: str) -> bool:
            return (topics is None or topic in topics) and (roles is None or role in roles)

        if self.recovered:
            yield from self._recover(wanted, tally)
        else:
            yield from self._read_finished(wanted)

    def _read_finished(self, wanted: Callable[[str, str], bool]) -> Iterator[RawMessage]:
        """Through the summary's chunk index, reading only chunks that hold wanted channels.

        Every chunk read is checked against its CRC. Uncompressed chunks (ours) are walked
        record by record without building an object per message; anything else goes
        through the mcap library.
        """
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
        indexes = sorted(
            (
                index
                for index in summary.chunk_indexes
                if not index.message_index_offsets or chosen.keys() & index.message_index_offsets
            ),
            key=lambda index: index.chunk_start_offset,
        )
        with open(self.path, "rb") as f:
            for index in indexes:
                try:
                    yield from self._finished_chunk(f, index, chosen)
                except RecordingError as exc:  # skip it, keep reading, tell the caller
                    self.damage.append(str(exc))

    def _finished_chunk(
        self, f: IO[bytes], index: Any, chosen: dict[int, tuple[str, str]]
    ) -> Iterator[RawMessage]:
        from mcap.data_stream import ReadDataStream
        from mcap.records import Chunk, Message
        from mcap.stream_reader import breakup_chunk

        where = f"{self.path}: damaged recording: chunk at byte {index.chunk_start_offset}"
        f.seek(index.chunk_start_offset)
        raw = f.read(index.chunk_length)
        if len(raw) < index.chunk_length or raw[0] != OPCODE_CHUNK:
            raise RecordingError(f"{where} is missing")
        try:
            chunk = Chunk.read(ReadDataStream(io.BytesIO(raw[9:])))
        except Exception as exc:  # a record that does not parse
            raise RecordingError(f"{where} does not parse ({exc})") from None
        if not _intact(chunk):
            try:
                records = breakup_chunk(chunk, validate_crc=True)
            except Exception as exc:  # CRC mismatch or an unreadable compression
                raise RecordingError(f"{where}: {exc}") from None
            for record in records:
                if isinstance(record, Message) and record.channel_id in chosen:
                    topic, role = chosen[record.channel_id]
                    yield RawMessage(topic, role, record.log_time, record.data)
            return
        data = chunk.data
        pos, size = 0, len(data)
        unpack_record, unpack_message = _RECORD_HEAD.unpack_from, _MESSAGE_HEAD.unpack_from
        while pos + 9 <= size:
            opcode, length = unpack_record(data, pos)
            body, end = pos + 9, pos + 9 + length
            if end > size:
                raise RecordingError(f"{where} has a record running past its end")
            if opcode == OPCODE_MESSAGE and length >= 22:
                channel_id, _, log_time = unpack_message(data, body)
                known = chosen.get(channel_id)
                if known is not None:
                    yield RawMessage(known[0], known[1], log_time, data[body + 22 : end])
            pos = end

    def _read_with_library(self, wanted: Callable[[str, str], bool]) -> Iterator[RawMessage]:
        """Files without a chunk index (other writers): the mcap library reads them."""
        from mcap.exceptions import McapError
        from mcap.reader import make_reader
        from mcap.stream_reader import CRCValidationError

        roles: dict[int, str] = {}
        try:
            with open(self.path, "rb") as f:
                reader = make_reader(f, validate_crcs=True)
                for _, channel, message in reader.iter_messages(log_time_order=False):
                    role = roles.get(channel.id)
                    if role is None:
                        role = roles[channel.id] = channel_role(channel.topic, channel.metadata)
                    if wanted(channel.topic, role):
                        yield RawMessage(channel.topic, role, message.log_time, message.data)
        except (CRCValidationError, McapError, struct.error, ValueError) as exc:
            raise RecordingError(f"{self.path}: damaged recording: {exc}") from None

    def _recover(
        self, wanted: Callable[[str, str], bool], tally: Tally | None
    ) -> Iterator[RawMessage]:
        from mcap.data_stream import ReadDataStream
        from mcap.records import Channel, Chunk, DataEnd, Footer, Message, Schema
        from mcap.stream_reader import StreamReader, breakup_chunk

        report = Recovery(total_bytes=self.size, good_bytes=len(MAGIC))
        self.recovery = report
        channels: dict[int, tuple[str, str]] = {}
        schemas: dict[int, str] = {}

        def handle(record: Any) -> Iterator[RawMessage]:
            if isinstance(record, Schema):
                schemas[record.id] = record.name
            elif isinstance(record, Channel):
                channels[record.id] = (
                    record.topic,
                    channel_role(record.topic, dict(record.metadata)),
                )
                self.recovered_schemas[record.topic] = schemas.get(record.schema_id, "")
            elif isinstance(record, Message):
                known = channels.get(record.channel_id)
                if known is not None:
                    report.messages += 1
                    if tally is not None:
                        tally(known[0], known[1], record.log_time)
                    if wanted(*known):
                        yield RawMessage(known[0], known[1], record.log_time, record.data)

        def walk(data: bytes) -> Iterator[RawMessage]:
            """The records of an uncompressed chunk, without an object per message."""
            pos, size = 0, len(data)
            chosen: dict[int, bool] = {}
            while pos + 9 <= size:
                opcode, length = _RECORD_HEAD.unpack_from(data, pos)
                body, end = pos + 9, pos + 9 + length
                if end > size:
                    break
                if opcode == OPCODE_MESSAGE and length >= 22:
                    channel_id, _, log_time = _MESSAGE_HEAD.unpack_from(data, body)
                    known = channels.get(channel_id)
                    if known is not None:
                        report.messages += 1
                        if tally is not None:
                            tally(known[0], known[1], log_time)
                        take = chosen.get(channel_id)
                        if take is None:
                            take = chosen[channel_id] = wanted(*known)
                        if take:
                            yield RawMessage(known[0], known[1], log_time, data[body + 22 : end])
                elif opcode == OPCODE_SCHEMA:
                    yield from handle(Schema.read(ReadDataStream(io.BytesIO(data[body:end]))))
                elif opcode == OPCODE_CHANNEL:
                    yield from handle(Channel.read(ReadDataStream(io.BytesIO(data[body:end]))))
                    chosen.clear()
                pos = end

        with open(self.path, "rb") as f:
            reader = StreamReader(f, emit_chunks=True, record_size_limit=RECORD_SIZE_LIMIT)
            records = reader.records
            while True:
                try:
                    record = next(records)
                except StopIteration:
                    break
                except Exception as exc:  # the unfinished tail: any parse error ends the data
                    if report.good_bytes < self.size:
                        report.reason = f"stopped at byte {report.good_bytes}: {_why(exc)}"
                    break
                if isinstance(record, Chunk):
                    if _intact(record):
                        report.good_bytes = f.tell()
                        try:
                            yield from walk(record.data)
                        except (struct.error, ValueError, UnicodeDecodeError):
                            report.damaged_chunks += 1
                        continue
                    inner = _chunk_records(record, breakup_chunk)
                    if inner is None:
                        if f.tell() >= self.size:  # the last, half-written chunk
                            break
                        report.damaged_chunks += 1
                        report.good_bytes = f.tell()
                        continue
                    report.good_bytes = f.tell()
                    for item in inner:
                        yield from handle(item)
                    continue
                report.good_bytes = f.tell()
                if isinstance(record, (DataEnd, Footer)):
                    report.data_complete = True
                    report.reason = "data section complete, summary missing or damaged"
                    break
                yield from handle(record)

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
        unreadable input lines), in file order: what to feed a Decoder to decode again."""
        wanted = {*RAW_TOPICS, TOPIC_DIAGNOSTICS}
        for message in self.messages(topics=wanted, roles={ROLE_RAW, ROLE_EVENT}):
            try:
                obj = json.loads(message.data)
                item = raw_item(message.topic, obj)
                if item is not None:
                    yield item
                elif isinstance(obj, dict) and obj.get("kind") in SOURCE_KINDS:
                    obj.setdefault("topic", message.topic)
                    obj.setdefault("time", message.log_time / 1e9)
                    yield Event.from_dict(obj)
            except (ValueError, KeyError, TypeError):
                continue

    def events(self) -> Iterator[Event]:
        """The decoded events as recorded."""
        for message in self.messages(roles={ROLE_EVENT}):
            try:
                obj = json.loads(message.data)
                if not isinstance(obj, dict):
                    continue
                obj.setdefault("topic", message.topic)
                obj.setdefault("time", message.log_time / 1e9)
                yield Event.from_dict(obj)
            except (ValueError, KeyError, TypeError):
                continue


def _why(exc: BaseException) -> str:
    text = str(exc)
    name = type(exc).__name__
    if name == "EndOfFile" or not text:
        return "end of file inside a record (recording not finished)"
    return f"{name}: {text}"


def _intact(chunk: Any) -> bool:
    """An uncompressed chunk that is complete and passes its CRC (walked directly)."""
    if chunk.compression != "" or len(chunk.data) != chunk.uncompressed_size:
        return False
    return not chunk.uncompressed_crc or zlib.crc32(chunk.data) == chunk.uncompressed_crc


def _chunk_records(chunk: Any, breakup: Callable[..., list[Any]]) -> list[Any] | None:
    """Records of a complete, intact chunk; None when it is cut short or fails its CRC."""
    if chunk.compression == "" and len(chunk.data) != chunk.uncompressed_size:
        return None
    if (
        chunk.compression == ""
        and chunk.uncompressed_crc
        and zlib.crc32(chunk.data) != chunk.uncompressed_crc
    ):
        return None
    try:
        return breakup(chunk, validate_crc=True)
    except Exception:  # damaged content or a compression we cannot read
        return None


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
