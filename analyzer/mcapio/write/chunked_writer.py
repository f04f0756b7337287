"""A lean chunked MCAP writer: the per-message path is one struct.pack into the open chunk.

It writes the same file layout as ``mcap.writer.Writer`` with chunking, all indexes,
statistics, summary offsets and CRCs (chunk, summary and data section); chunks are
compressed with zstd (default), lz4 or not at all. The rarely written records (header,
schema, channel, metadata, summary) are serialised by the mcap library's own record
classes; only messages and message indexes, which are written for every frame, are packed
here. Tests check every file with the mcap reader.

Messages come out in log-time order, as readers that stream a file expect: a chunk whose
messages arrived out of order is sorted before it is written, and a message older than a
chunk already written takes that chunk's end as its log time (its publish time keeps its
own; ``retimed`` counts them). With a ``hold_back`` (live recordings of sources that
arrive late, such as camera frames) a flush closes only the messages older than the
newest by more than the hold-back; the newer ones stay in the open chunk, so a message
late by less than that still takes its own place and time.
"""

from __future__ import annotations

import errno
import struct
import zlib
from collections import Counter
from collections.abc import Iterable
from typing import IO

from mcap.opcode import Opcode
from mcap.records import (
    Channel,
    Chunk,
    ChunkIndex,
    Header,
    Metadata,
    MetadataIndex,
    Schema,
    Statistics,
)

from analyzer.mcapio.write.chunk_order import (
    HoldBack,
    messages_in_order,
    rebuild,
    split_by_time,
)
from analyzer.mcapio.write.compression import compressor
from analyzer.mcapio.write.options import DEFAULT_COMPRESSION
from analyzer.mcapio.write.summary_tail import MAGIC, serialise, summary_tail

# Message record: opcode, record length, channel id, sequence, log time, publish time.
_MESSAGE = struct.Struct("<BQHIQQ")
_MESSAGE_FIXED = 2 + 4 + 8 + 8
_OPCODE_MESSAGE = int(Opcode.MESSAGE)  # a plain int packs faster than the IntEnum
# Message index record head: opcode, record length, channel id, byte length of the pairs.
_INDEX_HEAD = struct.Struct("<BQHI")

# A provisional summary up to this size is rewritten at every live flush; a larger one only
# once as many data bytes followed it (so it at most doubles what is written).
LIVE_SUMMARY_FREE = 256 * 1024
# With a hold-back, an open chunk holding more than this is closed whole all the same
# (its newest messages then bound the file as without a hold-back): memory stays bounded.
HOLD_BACK_MAX_BYTES = 16 * 1024 * 1024


class ChunkedWriter:
    """Writes an MCAP file to ``stream`` (binary, opened by the caller, not closed here)."""

    def __init__(
        self,
        stream: IO[bytes],
        *,
        chunk_size: int = 128 * 1024,
        compression: str = DEFAULT_COMPRESSION,
        live_summary: bool = False,
        hold_back: int = 0,
    ) -> None:
        self._stream = stream
        # Messages within ``hold_back`` ns of the newest log time stay in the open chunk
        # when it is closed by a flush or by its size (0: every message is closed at once).
        # (Few attributes: past 30, CPython's attribute access on the hot path slows down.)
        self._hold = HoldBack(hold_back)
        # Live recording: every flush also writes a provisional summary and footer after the
        # data (overwritten by the next chunk), so a killed recorder leaves an indexed file.
        self._live_summary = live_summary
        self._tail_at: int | None = None  # where the provisional summary starts, if written
        self._since_tail = 0  # data bytes written since the last provisional summary
        self._chunk_size = chunk_size
        self._close_at = chunk_size  # open chunk size at which it is closed
        self._compression, self._compress = compressor(compression)
        self.retimed = 0  # messages whose log time was raised to keep the file in order
        self.retimed_topics: Counter[str] = Counter()  # the same, by topic
        self._floor = 0  # end time of the last chunk written: no message may go below it
        self._pos = 0
        self._data_crc = 0
        self._schemas: dict[int, Schema] = {}
        self._channels: dict[int, Channel] = {}
        self._chunk_indexes: list[bytes] = []  # serialised once: summaries repeat them
        self._metadata_indexes: list[bytes] = []
        self._channel_counts: dict[int, int] = {}
        self._message_count = 0
        self._chunk_count = 0
        self._metadata_count = 0
        self._start_time = 0
        self._end_time = 0
        # the open chunk
        self._chunk = bytearray()
        self._index: dict[int, list[int]] = {}  # channel id -> [log_time, offset, ...]
        self._chunk_last = 0  # highest log time in the open chunk
        self._unsorted = False  # a message of the open chunk is older than one before it
        self._records: list[bytes] = []  # schema / channel records of the open chunk

    # -- low level -------------------------------------------------------------------------------

    def _write_all(self, data: bytes | bytearray | memoryview) -> None:
        """Write every byte or raise (an unbuffered stream may take only part of a write)."""
        view = memoryview(data)
        while view:
            written = self._stream.write(view)
            if not written:
                raise OSError(errno.EIO, "the file accepted no more data")
            view = view[written:]

    def _write(self, data: bytes | bytearray | memoryview) -> None:
        """Write a data-section record. ``position`` moves only once all of it is written."""
        if self._tail_at is not None:
            self._drop_tail()
        self._write_all(data)
        self._since_tail += len(data)
        self._data_crc = zlib.crc32(data, self._data_crc)
        self._pos += len(data)

    @property
    def position(self) -> int:
        """End of the last record written completely (a failed write leaves less on disk)."""
        return self._pos

    @property
    def message_count(self) -> int:
        """Messages in the chunks written completely."""
        return self._message_count

    @property
    def end_time(self) -> int:
        """Newest log time (ns) in the chunks written completely (0 before the first)."""
        return self._end_time

    def drop_open_chunk(self) -> None:
        """Forget the chunk being built (after a write error it cannot be written). If its
        write failed after the hold-back kept newer messages out of it, those become the
        open chunk, for one more try (``finish``); a second call forgets them too."""
        self._chunk = bytearray()
        self._index = {}
        self._records = []
        self._chunk_last = self._floor
        self._unsorted = False
        self._close_at = self._chunk_size
        hold = self._hold
        if hold.held_over is not None:
            self._chunk, self._index, self._chunk_last, in_order = hold.held_over
            self._unsorted = not in_order
            hold.held_over = None

    @staticmethod
    def _record(record: object) -> bytes:
        return serialise(record)

    # -- public API (a subset of mcap.writer.Writer) -----------------------------------------------

    def start(self, profile: str = "", library: str = "") -> None:
        self._write(MAGIC)
        self._write(self._record(Header(profile=profile, library=library)))

    def register_schema(self, name: str, encoding: str, data: bytes) -> int:
        schema_id = len(self._schemas) + 1
        schema = Schema(id=schema_id, name=name, encoding=encoding, data=data)
        self._schemas[schema_id] = schema
        self._add_record(self._record(schema))
        return schema_id

    def register_channel(
        self,
        topic: str,
        message_encoding: str,
        schema_id: int,
        metadata: dict[str, str] | None = None,
    ) -> int:
        channel_id = len(self._channels) + 1
        channel = Channel(
            id=channel_id,
            topic=topic,
            message_encoding=message_encoding,
            schema_id=schema_id,
            metadata=dict(metadata or {}),
        )
        self._channels[channel_id] = channel
        self._channel_counts[channel_id] = 0
        self._add_record(self._record(channel))
        return channel_id

    def _add_record(self, record: bytes) -> None:
        self._chunk += record
        self._records.append(record)

    def add_message(
        self, channel_id: int, log_time: int, data: bytes, publish_time: int, sequence: int = 0
    ) -> None:
        self.add_messages(((channel_id, log_time, data, publish_time, sequence),))

    def add_messages(self, messages: Iterable[tuple[int, int, bytes, int, int]]) -> None:
        """``add_message`` of each (channel id, log time, data, publish time, sequence), in
        order: one call per batch, the open chunk's state in local variables (this runs
        for every message of a file)."""
        pack = _MESSAGE.pack
        chunk, index_of, last, floor = self._chunk, self._index, self._chunk_last, self._floor
        close_at = self._close_at
        for channel_id, log_time, data, publish_time, sequence in messages:
            if log_time < last:
                if log_time < floor:
                    log_time = floor  # older than a chunk on disk already
                    self.retimed += 1
                    self.retimed_topics[self._channels[channel_id].topic] += 1
                if log_time < last:
                    self._unsorted = True
            else:
                last = log_time
            index = index_of.get(channel_id)
            if index is None:
                index = index_of[channel_id] = []
            index += (log_time, len(chunk))
            chunk += pack(
                _OPCODE_MESSAGE,
                _MESSAGE_FIXED + len(data),
                channel_id,
                sequence,
                log_time,
                publish_time,
            )
            chunk += data
            if len(chunk) >= close_at:
                self._chunk_last = last
                self._chunk_full()
                chunk, index_of, last = self._chunk, self._index, self._chunk_last
                floor, close_at = self._floor, self._close_at
        self._chunk_last = last

    def add_metadata(self, name: str, data: dict[str, str]) -> None:
        record = self._record(Metadata(name=name, metadata=dict(data)))
        offset = self._pos
        self._write(record)
        index = MetadataIndex(offset=offset, length=len(record), name=name)
        self._metadata_indexes.append(self._record(index))
        self._metadata_count += 1

    def flush(self) -> None:
        """Close the open chunk (if it holds messages) and flush the stream.

        With a hold-back only the messages older than the newest by more than it are
        closed, unless nothing came since the last flush (then all of them are). With
        ``live_summary`` a provisional summary and footer follow the data, so the file is
        complete as it stands; the next data written replaces them. To bound the extra
        writes of a long recording, a summary larger than ``LIVE_SUMMARY_FREE`` is written
        again only once at least as many data bytes have followed the previous one."""
        hold = self._hold
        if not hold.window:
            self._finish_chunk()
        elif self._message_count + self.held_messages == hold.given_at_flush:
            self._finish_chunk()  # nothing came since the last flush: all of it goes out
        else:
            self._close_older()
        hold.given_at_flush = self._message_count + self.held_messages
        if self._live_summary and self._tail_at is None and self._message_count:
            tail = self._tail(self._pos)
            if len(tail) <= LIVE_SUMMARY_FREE or self._since_tail >= len(tail):
                self._write_all(tail)  # not data: position and the data CRC stay
                self._tail_at = self._pos
                self._since_tail = 0
        self._stream.flush()

    def finish(self) -> None:
        """Write the last chunk (held-back messages too), the data end, the summary and
        the footer."""
        self._finish_chunk()
        if self._tail_at is not None:
            self._drop_tail()
        self._write_all(self._tail(self._pos))
        self._stream.flush()

    def _drop_tail(self) -> None:
        """Cut the provisional summary off; new data goes where it was."""
        assert self._tail_at is not None
        self._stream.seek(self._tail_at)
        self._stream.truncate()
        self._tail_at = None

    def _tail(self, data_end: int) -> bytes:
        """DataEnd, summary, summary offsets, footer and magic for data ending at ``data_end``."""
        statistics = Statistics(
            message_count=self._message_count,
            schema_count=len(self._schemas),
            channel_count=len(self._channels),
            attachment_count=0,
            metadata_count=self._metadata_count,
            chunk_count=self._chunk_count,
            message_start_time=self._start_time,
            message_end_time=self._end_time,
            channel_message_counts={k: v for k, v in self._channel_counts.items() if v},
        )
        return summary_tail(
            data_end,
            self._data_crc,
            [
                (Opcode.SCHEMA, [self._record(s) for s in self._schemas.values()]),
                (Opcode.CHANNEL, [self._record(c) for c in self._channels.values()]),
                (Opcode.STATISTICS, [self._record(statistics)]),
                (Opcode.CHUNK_INDEX, self._chunk_indexes),
                (Opcode.METADATA_INDEX, self._metadata_indexes),
            ],
        )

    # -- chunks ----------------------------------------------------------------------------------

    @property
    def held_messages(self) -> int:
        """Messages in the open chunk, not on disk yet (held back or not yet flushed)."""
        return sum(len(pairs) for pairs in self._index.values()) // 2

    def _chunk_full(self) -> None:
        """The open chunk reached its size: closed, less what the hold-back keeps open."""
        if not self._hold.window or len(self._chunk) > HOLD_BACK_MAX_BYTES:
            self._finish_chunk()
        else:
            self._close_older()

    def _close_older(self) -> None:
        """Close the messages of the open chunk older than the newest by more than the
        hold-back into a chunk of their own (in log-time order); the others stay open."""
        if not self._index:
            return
        cutoff = self._chunk_last - self._hold.window
        head = b"".join(self._records)
        split = split_by_time(self._chunk, head, self._index, cutoff, not self._unsorted)
        if split is None:
            self._finish_chunk()  # nothing is held back
            return
        closed, closed_index, held, held_index, held_in_order = split
        if closed_index:
            newest = self._chunk_last
            self._chunk, self._index = closed, closed_index
            self._unsorted = False
            # kept should the write fail
            self._hold.held_over = (held, held_index, newest, held_in_order)
            self._finish_chunk()
            self._hold.held_over = None
            self._chunk, self._index = held, held_index
            self._chunk_last = newest
            self._unsorted = not held_in_order
        # The held messages stay. The next close by size comes after a chunk's size of new
        # data, or as much as is held if that is more: each close copies what is held, so
        # the copying stays within the size of the data written.
        held_size = len(self._chunk)
        self._close_at = held_size + max(self._chunk_size, held_size)

    def _finish_chunk(self) -> None:
        if not self._index:
            return
        if self._unsorted:
            self._sort_chunk()
        data = bytes(self._chunk)
        start = min(min(pairs[0::2]) for pairs in self._index.values())
        end = max(max(pairs[0::2]) for pairs in self._index.values())
        stored = data if self._compress is None else self._compress(data)
        chunk = Chunk(
            compression=self._compression,
            data=stored,
            message_start_time=start,
            message_end_time=end,
            uncompressed_crc=zlib.crc32(data),
            uncompressed_size=len(data),
        )
        chunk_record = self._record(chunk)
        chunk_offset = self._pos
        index_offset = chunk_offset + len(chunk_record)
        offsets: dict[int, int] = {}
        index_parts: list[bytes] = []
        position = index_offset
        for channel_id, pairs in self._index.items():
            count = len(pairs)
            record = _INDEX_HEAD.pack(
                Opcode.MESSAGE_INDEX, 2 + 4 + 8 * count, channel_id, 8 * count
            ) + struct.pack(f"<{count}Q", *pairs)
            offsets[channel_id] = position
            index_parts.append(record)
            position += len(record)
        indexes = b"".join(index_parts)
        # Everything of the chunk goes out in one write: a crash cuts at most this tail, and
        # nothing below is counted unless the whole chunk was written.
        self._write(chunk_record + indexes)
        messages = 0
        for channel_id, pairs in self._index.items():
            self._channel_counts[channel_id] += len(pairs) // 2
            messages += len(pairs) // 2
        self._chunk_indexes.append(
            self._record(
                ChunkIndex(
                    message_start_time=start,
                    message_end_time=end,
                    chunk_start_offset=chunk_offset,
                    chunk_length=len(chunk_record),
                    message_index_offsets=offsets,
                    message_index_length=len(indexes),
                    compression=self._compression,
                    compressed_size=len(stored),
                    uncompressed_size=len(data),
                )
            )
        )
        if self._message_count == 0:
            self._start_time, self._end_time = start, end
        else:
            self._start_time = min(self._start_time, start)
            self._end_time = max(self._end_time, end)
        self._message_count += messages
        self._chunk_count += 1
        self._chunk = bytearray()
        self._index = {}
        self._records = []
        self._floor = max(self._floor, end)
        self._chunk_last = self._floor
        self._unsorted = False
        self._close_at = self._chunk_size

    def _sort_chunk(self) -> None:
        """Rebuild the open chunk: its schema / channel records, then messages by log time."""
        head = b"".join(self._records)
        self._chunk, self._index = rebuild(self._chunk, head, messages_in_order(self._index))
