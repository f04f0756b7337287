"""McapSink: writes raw items, decoded events and Foxglove views to a crash-tolerant MCAP file."""

from __future__ import annotations

import contextlib
import itertools
import json
import operator
import os
import threading
import time
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from analyzer import PROTOCOL_DOCUMENT, __version__, timefmt
from analyzer.errors import SourceError
from analyzer.mcapio.channels import (
    CAN_FRAME_SCHEMA,
    METADATA_NAME,
    ROLE_EVENT,
    ROLE_KEY,
    ROLE_RAW,
    ROLE_VIEW,
    STATS_METADATA_NAME,
    STREAM_BYTES_SCHEMA,
    TOPIC_CAN_FRAMES,
    TOPIC_STREAM_BYTES,
    can_frame_json,
    permissive_schema,
    schema_name,
    stream_chunk_json,
    time_ns,
)
from analyzer.mcapio.chunked_writer import ChunkedWriter
from analyzer.mcapio.foxglove import VIEW_INPUT_TOPICS, VIEW_SCHEMAS, FoxgloveViews
from analyzer.mcapio.options import DEFAULT_COMPRESSION
from analyzer.output_file import OutputFile, describe_os_error, is_disk_full
from analyzer.pipeline import Batch, RawItem
from analyzer.protocol.types import TOPIC_ANALYSIS_RESPONSE, CanFrame, Event
from analyzer.tally import Tally

# Small chunks: a crash loses at most the chunk being built, and the time-based flush
# closes chunks long before they fill up in live use.
DEFAULT_CHUNK_SIZE = 128 * 1024
# Live recording: close the open chunk and flush this often (seconds), so that after a
# crash everything older than about a second is on disk.
DEFAULT_FLUSH_INTERVAL = 0.5


def _default_schemas() -> dict[str, dict[str, Any]]:
    try:
        from analyzer.protocol.schema import topic_schemas
    except ImportError:
        return {}
    return topic_schemas()


def _json_default(value: Any) -> Any:
    if isinstance(value, (bytes, bytearray, memoryview)):
        return bytes(value).hex(" ").upper()
    if isinstance(value, (set, frozenset, tuple)):
        return list(value)
    return str(value)


# One encoder for every message (json.dumps with options builds a new one per call).
# Events never hold reference cycles, so the cycle check is skipped.
_ENCODE = json.JSONEncoder(
    separators=(",", ":"), default=_json_default, check_circular=False
).encode


_time_of = operator.attrgetter("time")


def _is_event(value: object) -> bool:
    return isinstance(value, Event)


class McapSink:
    """Sink (see analyzer.pipeline) writing one MCAP recording.

    Channels: one JSON channel per event topic (schema encoding ``jsonschema``), the lossless
    raw channels ``/can/frames`` and ``/stream/bytes``, and Foxglove views (``foxglove.LocationFix``
    for UAV and ranging-target positions, ``foxglove.Log`` for diagnostics). Log and publish
    time of every message are the event / item time in nanoseconds.

    With ``flush_interval`` set (live recording) the open chunk is closed and the file flushed
    at that interval by a background thread (and by ``handle``), followed by a provisional
    summary and footer, and fsync'ed, so a killed recorder leaves a complete, indexed file of
    everything up to the last flush (only its closing stats record is missing). A write error
    (disk full, device gone), in the caller's thread or the flush thread, stops the recording: every
    chunk written completely stays in the file (finished with a summary when there is room),
    ``error`` says what happened and how much was kept, and a ``SourceError`` is raised once,
    by the next ``handle`` / ``flush`` / ``close``.

    The file is created through ``OutputFile`` (``force``, ``inputs``, ``replaceable``,
    ``atomic`` as there): directly at its name by default, so a killed recorder leaves it
    there; ``atomic=True`` writes a temporary file renamed by ``close``.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        metadata: dict[str, str],
        schemas: dict[str, dict[str, Any]] | None = None,
        chunk_size: int = DEFAULT_CHUNK_SIZE,
        flush_interval: float | None = DEFAULT_FLUSH_INTERVAL,
        foxglove_views: bool = True,
        compression: str = DEFAULT_COMPRESSION,
        clock: Callable[[], float] = time.monotonic,
        force: bool = True,
        inputs: Iterable[str | os.PathLike[str]] = (),
        replaceable: Callable[[Path], bool] | None = None,
        atomic: bool = False,
    ) -> None:

        self.path = str(path)
        self.error: str | None = None  # the full message after a write error
        self.error_reason: str | None = None  # just the reason ("No space left on device")
        self.kept_messages = 0  # after a write error: messages the file still holds
        self.kept_until: float | None = None  # ... and the newest log time among them
        self.tally = Tally()  # the run's figures, written as a metadata record at the end
        self.items_written = 0
        self.events_written = 0
        self.messages_written = 0
        self.last_time: float | None = None
        self._schemas = _default_schemas() if schemas is None else dict(schemas)
        self._views = FoxgloveViews() if foxglove_views else None
        self._clock = clock
        self._flush_interval = flush_interval
        self._lock = threading.Lock()
        self._closed = False
        self._reported = False  # the write error was raised to a caller once
        self._channels: dict[str, int] = {}
        self._schema_ids: dict[str, int] = {}
        self._sequence: dict[int, int] = {}
        self._dirty = False
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        # Unbuffered: every chunk is one write, so a failed write leaves whole chunks before it.
        self._output = OutputFile(
            path, force=force, inputs=inputs, replaceable=replaceable, atomic=atomic, buffered=False
        )
        self._file = self._output.binary
        info = {
            "tool": "gimbal-analyzer",
            "tool_version": __version__,
            "protocol_document": PROTOCOL_DOCUMENT,
            **{str(k): str(v) for k, v in metadata.items()},
        }
        try:
            self._writer = ChunkedWriter(
                self._file,
                chunk_size=chunk_size,
                compression=compression,
                live_summary=flush_interval is not None,
            )
            self._writer.start(profile="", library=f"gimbal-analyzer {__version__}")
            self._writer.add_metadata(METADATA_NAME, info)
        except OSError as exc:
            self._stop_after(exc)
            self._reported = True
            raise SourceError(self.error) from None
        except BaseException:  # Ctrl-C / SIGTERM, a bad option: leave nothing behind
            self._output.discard()
            raise
        self._last_flush = clock()
        if flush_interval is not None:
            self._thread = threading.Thread(target=self._flush_loop, name="mcap-flush", daemon=True)
            self._thread.start()

    # -- Sink ------------------------------------------------------------------------------------

    def handle(self, batch: Batch) -> None:
        with self._lock:
            if self._closed:
                self._raise_pending()
                return
            try:
                self._write_batch(batch.items, batch.events)
                if (
                    self._flush_interval is not None
                    and self._clock() - self._last_flush >= self._flush_interval
                ):
                    self._flush_locked()
            except OSError as exc:
                self._stop_after(exc)
                self._raise_pending()

    def write_item(self, item: RawItem) -> None:
        """Write one raw CAN frame / stream chunk to its lossless channel."""
        with self._lock:
            if self._closed:
                return
            try:
                self._write_items([item])
            except OSError as exc:
                self._stop_after(exc)
                self._raise_pending()

    def write_event(self, event: Event) -> None:
        """Write one decoded event (and its Foxglove views)."""
        with self._lock:
            if self._closed:
                return
            try:
                self._write_events([event])
            except OSError as exc:
                self._stop_after(exc)
                self._raise_pending()

    def write_with(self, write: Callable[[ChunkedWriter], None]) -> None:
        """Run ``write`` on the file's writer under the sink's lock, for channels other
        modules own (camera video); a write error stops the recording as ``handle`` does."""
        with self._lock:
            if self._closed:
                self._raise_pending()
                return
            try:
                write(self._writer)
                self._dirty = True
            except OSError as exc:
                self._stop_after(exc)
                self._raise_pending()

    def flush(self) -> None:
        """Close the open chunk and push everything to the operating system."""
        with self._lock:
            if self._closed:
                return
            try:
                self._flush_locked()
            except OSError as exc:
                self._stop_after(exc)
                self._raise_pending()

    def close(self) -> None:
        """Finish the file (summary, indexes, statistics). Safe to call twice.

        Raises SourceError once if a write error stopped the recording and no call to
        ``handle`` has reported it yet."""
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join()
        with self._lock:
            if self._closed:
                self._raise_pending()
                return
            try:
                self._writer.add_metadata(STATS_METADATA_NAME, self.tally.to_metadata())
                self._writer.finish()
                os.fsync(self._file.fileno())
            except OSError as exc:
                self._stop_after(exc)
                self._raise_pending()
                return
            self._closed = True
            try:
                self._output.commit() if self._output.atomic else self._output.close_keep()
            except SourceError as exc:
                self.error = self.error_reason = str(exc)
                self._reported = True
                raise

    def abandon(self) -> None:
        """Stop after a failure elsewhere (bad input, Ctrl-C): an atomic output's temporary
        file is removed, a direct one is finished like ``close`` does."""
        if not self._output.atomic:
            with contextlib.suppress(SourceError):
                self.close()
            return
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join()
        with self._lock:
            self._closed = True
            self._output.discard()

    @property
    def retimed(self) -> int:
        """Messages older than a chunk already written, logged at that chunk's end time."""
        return self._writer.retimed

    @property
    def retimed_input(self) -> int:
        """``retimed`` less the response findings, which are judged after their command's
        time by nature: what says that the input itself went back in time."""
        return self._writer.retimed - self._writer.retimed_topics[TOPIC_ANALYSIS_RESPONSE]

    @property
    def closed(self) -> bool:
        return self._closed

    # -- writing ---------------------------------------------------------------------------------

    def _channel(self, topic: str, role: str) -> int:
        channel_id = self._channels.get(topic)
        if channel_id is not None:
            return channel_id
        if role == ROLE_RAW:
            schema = CAN_FRAME_SCHEMA if topic == TOPIC_CAN_FRAMES else STREAM_BYTES_SCHEMA
            name = str(schema["title"])
        elif role == ROLE_VIEW:
            name, schema = VIEW_SCHEMAS[topic]
        else:
            name = schema_name(topic)
            schema = self._schemas.get(topic) or permissive_schema(topic)
        schema_id = self._schema_ids.get(name)
        if schema_id is None:
            data = json.dumps(schema, separators=(",", ":")).encode()
            schema_id = self._writer.register_schema(name, "jsonschema", data)
            self._schema_ids[name] = schema_id
        channel_id = self._writer.register_channel(topic, "json", schema_id, {ROLE_KEY: role})
        self._channels[topic] = channel_id
        self._sequence[channel_id] = 0
        return channel_id

    def _write_batch(self, items: list[RawItem], events: list[Event]) -> None:
        """Items and events of one batch, merged in time order (an item before its events)."""
        if not events or (items and items[-1].time <= events[0].time):
            self._write_items(items)
            self._write_events(events)
            return
        if not items:
            self._write_events(events)
            return
        merged: list[RawItem | Event] = sorted([*items, *events], key=_time_of)
        for is_event, run in itertools.groupby(merged, key=_is_event):
            if is_event:
                self._write_events(list(run))  # type: ignore[arg-type]
            else:
                self._write_items(list(run))  # type: ignore[arg-type]

    def _write_items(self, items: list[RawItem]) -> None:
        add = self._writer.add_message
        sequence = self._sequence
        can_id = self._channels.get(TOPIC_CAN_FRAMES, 0)
        stream_id = self._channels.get(TOPIC_STREAM_BYTES, 0)
        for item in items:
            if isinstance(item, CanFrame):
                channel_id = can_id or self._channel(TOPIC_CAN_FRAMES, ROLE_RAW)
                can_id = channel_id
                data = can_frame_json(item)
            else:
                channel_id = stream_id or self._channel(TOPIC_STREAM_BYTES, ROLE_RAW)
                stream_id = channel_id
                data = stream_chunk_json(item)
            log_time = time_ns(item.time)
            number = sequence[channel_id] + 1
            sequence[channel_id] = number
            add(channel_id, log_time, data, log_time, number)
            self.messages_written += 1
            self.items_written += 1
        self.tally.add_items(items)
        if items:
            self._dirty = True
            self.last_time = items[-1].time

    def _write_events(self, events: list[Event]) -> None:
        add = self._writer.add_message
        sequence = self._sequence
        channels = self._channels
        views = self._views
        for event in events:
            topic = event.topic
            channel_id = channels.get(topic) or self._channel(topic, ROLE_EVENT)
            log_time = time_ns(event.time)
            number = sequence[channel_id] + 1
            sequence[channel_id] = number
            add(channel_id, log_time, _ENCODE(event.to_dict()).encode(), log_time, number)
            self.messages_written += 1
            self.events_written += 1
            if views is not None and topic in VIEW_INPUT_TOPICS:
                for view_topic, message in views.views(event):
                    view_id = channels.get(view_topic) or self._channel(view_topic, ROLE_VIEW)
                    number = sequence[view_id] + 1
                    sequence[view_id] = number
                    add(view_id, log_time, _ENCODE(message).encode(), log_time, number)
                    self.messages_written += 1
        self.tally.add_events(events)
        if events:
            self._dirty = True
            self.last_time = events[-1].time

    def _flush_locked(self) -> None:
        self._last_flush = self._clock()
        if not self._dirty:
            return
        self._writer.flush()
        self._dirty = False

    def _flush_loop(self) -> None:
        interval = self._flush_interval or DEFAULT_FLUSH_INTERVAL
        while not self._stop.wait(interval / 4):
            flushed = False
            with self._lock:
                if self._closed:
                    return
                if self._clock() - self._last_flush >= interval:
                    try:
                        flushed = self._dirty
                        self._flush_locked()
                    except OSError as exc:
                        self._stop_after(exc)  # the next handle() raises it to the capture
                        return
                fd = self._file.fileno() if flushed else -1
            if fd >= 0:
                try:
                    os.fsync(fd)  # outside the lock: slow media must not stall capture
                except OSError as exc:
                    with self._lock:
                        if not self._closed:
                            self._stop_after(exc)
                    return

    def _raise_pending(self) -> None:
        if self.error is not None and not self._reported:
            self._reported = True
            raise SourceError(self.error)

    def _stop_after(self, exc: OSError) -> None:
        """Stop for good after a write error, keeping every chunk written completely.

        The half-written tail is cut off and, if the space it freed allows, the file is
        finished (summary and statistics of what it holds), so it opens like any other
        recording; otherwise it is left as an unfinished recording the reader recovers.
        A file that keeps no message at all is removed, so it cannot block a rerun."""
        writer = self._writer
        reason = describe_os_error(exc)
        self.error_reason = reason
        self._closed = True
        self._stop.set()
        good = writer.position
        writer.drop_open_chunk()
        fd = self._file.fileno()
        try:
            os.ftruncate(fd, good)
            os.lseek(fd, good, os.SEEK_SET)
            if writer.message_count:
                writer.add_metadata(STATS_METADATA_NAME, self.tally.to_metadata())
                writer.finish()
            os.fsync(fd)
        except OSError:
            # No room for the closing records: try the summary alone (what a live flush
            # writes), so the file still opens indexed; else leave the complete chunks.
            end = writer.position
            try:
                os.ftruncate(fd, end)
                os.lseek(fd, end, os.SEEK_SET)
                if writer.message_count:
                    writer.finish()
            except OSError:
                with contextlib.suppress(OSError):
                    os.ftruncate(fd, end)
            with contextlib.suppress(OSError):
                os.fsync(fd)
        self.kept_messages = writer.message_count
        self.kept_until = writer.end_time / 1e9 if writer.message_count else None
        what = "disk full: cannot write" if is_disk_full(exc) else "cannot write"
        if self.kept_messages:
            self._output.close_keep()
            if self._output.atomic:
                self._output.discard()
                kept = "the unfinished output was removed"
            else:
                until = format_clock(self.kept_until)
                kept = f"{self.kept_messages} messages up to {until} kept in {self.path}"
        else:
            self._output.discard()
            kept = f"nothing was kept ({self.path} removed)"
        self.error = f"{what} {self.path} ({reason}); {kept}"


def format_clock(seconds: float | None) -> str:
    """HH:MM:SS.mmmZ (UTC) of a Unix time; seconds for small (relative) times."""
    if seconds is None:
        return "-"
    if not timefmt.is_absolute(seconds):  # a relative time, not a date
        return f"{seconds:.3f} s"
    return timefmt.format_clock(seconds)


def recording_metadata(source: str, **extra: str) -> dict[str, str]:
    """Metadata for a new recording: source description plus anything else worth keeping."""
    out = {"source": source, "created": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
    out.update(extra)
    return out
