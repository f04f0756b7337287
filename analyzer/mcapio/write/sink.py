"""McapSink: writes raw items, decoded events and Foxglove views to a crash-tolerant MCAP file."""

from __future__ import annotations

import contextlib
import os
import threading
import time
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from analyzer.errors import SourceError
from analyzer.mcapio.channels import METADATA_NAME, STATS_METADATA_NAME, MessageTee
from analyzer.mcapio.foxglove import FoxgloveViews
from analyzer.mcapio.write.channel_registry import ChannelRegistry, default_schemas
from analyzer.mcapio.write.chunked_writer import ChunkedWriter
from analyzer.mcapio.write.failure import format_clock, keep_complete_chunks
from analyzer.mcapio.write.message_writer import MessageWriter
from analyzer.mcapio.write.options import DEFAULT_COMPRESSION
from analyzer.output_file import OutputFile, describe_os_error, is_disk_full
from analyzer.pipeline import Batch, RawItem
from analyzer.protocol.types import TOPIC_ANALYSIS_RESPONSE, Event
from analyzer.tally import Tally
from analyzer.timefmt import UTC, TimeZone
from analyzer.version import PROTOCOL_DOCUMENT, __version__

__all__ = [
    "DEFAULT_CHUNK_SIZE",
    "DEFAULT_FLUSH_INTERVAL",
    "McapSink",
    "format_clock",
    "recording_metadata",
]

# Small chunks: a crash loses at most the chunk being built, and the time-based flush
# closes chunks long before they fill up in live use.
DEFAULT_CHUNK_SIZE = 128 * 1024
# Live recording: close the open chunk and flush this often (seconds), so that after a
# crash everything older than about a second is on disk.
DEFAULT_FLUSH_INTERVAL = 0.5


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

    ``hold_back`` (seconds) is for recordings with messages that reach the sink later than
    the telemetry of the same moment (camera frames): a flush leaves the messages within
    that much of the newest log time in the open chunk, so a late one still takes its own
    log time instead of the end of a chunk already written. A killed recorder then loses
    that much more. ``close`` writes them all; after a write error they are kept if they
    fit in the space the failed chunk freed (``kept_messages`` counts what the file holds);
    ``error`` says until when in ``zone`` (the time zone the user reads).
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
        tee: MessageTee | None = None,
        hold_back: float = 0.0,
        zone: TimeZone = UTC,
    ) -> None:

        self.path = str(path)
        self.zone = zone  # the time in the message of a write error (a message for people)
        self.error: str | None = None  # the full message after a write error
        self.error_reason: str | None = None  # just the reason ("No space left on device")
        self.kept_messages = 0  # after a write error: messages the file still holds
        self.kept_until: float | None = None  # ... and the newest log time among them
        self._schemas = default_schemas() if schemas is None else dict(schemas)
        self._views = FoxgloveViews() if foxglove_views else None
        self._tee = tee  # gets every channel and message written (the live server)
        self._clock = clock
        self._flush_interval = flush_interval
        self._lock = threading.Lock()
        self._closed = False
        self._reported = False  # the write error was raised to a caller once
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
                hold_back=round(hold_back * 1e9),
            )
            self._channels = ChannelRegistry(self._writer, self._schemas, self._tee)
            self._messages = MessageWriter(
                self._writer,
                self._channels,
                Tally(),
                self._views,
                self._tee,
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
                if batch.sequence == 0 and batch.counted is not None and self._thread is None:
                    self._messages.share_tally(batch.counted)  # counted once, not twice
                self._messages.write_batch(batch.items, batch.events)
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
                self._messages.write_items([item])
            except OSError as exc:
                self._stop_after(exc)
                self._raise_pending()

    def write_event(self, event: Event) -> None:
        """Write one decoded event (and its Foxglove views)."""
        with self._lock:
            if self._closed:
                return
            try:
                self._messages.write_events([event])
            except OSError as exc:
                self._stop_after(exc)
                self._raise_pending()

    def add_camera(self, name: str) -> None:
        """A camera stream is recorded: its optical frame hangs under the gimbal in /tf."""
        with self._lock:
            if self._views is not None:
                self._views.scene.add_camera(name)

    def add_overlay(self, topic: str, width: int, height: int, *, stroked: bool = False) -> None:
        """Draw the overlays (tracking box, taps, angles) on ``topic``, for a picture of
        ``width`` x ``height`` pixels, from now on (``stroked``: the text as lines)."""
        with self._lock:
            if self._views is not None:
                self._views.scene.add_overlay(topic, width, height, stroked=stroked)

    @property
    def tally(self) -> Tally:
        """The run's figures, written as a metadata record at the end: the pipeline's own
        counters when this sink got every batch from the first and no flush thread reads
        them (``handle``), else its own count of what it was given."""
        return self._messages.tally

    @property
    def tee(self) -> MessageTee | None:
        """What gets every channel and message written (the live server), if anything."""
        return self._tee

    def write_with(self, write: Callable[[ChannelRegistry], None]) -> None:
        """Run ``write`` with the file's channels under the sink's lock, for messages other
        modules make (camera video); a write error stops the recording as ``handle`` does."""
        with self._lock:
            if self._closed:
                self._raise_pending()
                return
            try:
                write(self._channels)
                self._messages.dirty = True
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

    @property
    def items_written(self) -> int:
        return self._messages.items_written

    @property
    def events_written(self) -> int:
        return self._messages.events_written

    @property
    def messages_written(self) -> int:
        """Messages given to the file (views included), written or still in the open chunk."""
        return self._messages.messages_written

    @property
    def last_time(self) -> float | None:
        """Time of the newest item or event written."""
        return self._messages.last_time

    # -- flushing --------------------------------------------------------------------------------

    def _flush_locked(self) -> None:
        self._last_flush = self._clock()
        if not self._messages.dirty:
            return
        self._writer.flush()
        # held-back messages go out at a later flush, even if nothing else comes
        self._messages.dirty = self._writer.held_messages > 0

    def _flush_loop(self) -> None:
        interval = self._flush_interval or DEFAULT_FLUSH_INTERVAL
        while not self._stop.wait(interval / 4):
            flushed = False
            with self._lock:
                if self._closed:
                    return
                if self._clock() - self._last_flush >= interval:
                    try:
                        flushed = self._messages.dirty
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
        keep_complete_chunks(writer, self._file.fileno(), self.tally.to_metadata)
        self.kept_messages = writer.message_count
        self.kept_until = writer.end_time / 1e9 if writer.message_count else None
        what = "disk full: cannot write" if is_disk_full(exc) else "cannot write"
        if self.kept_messages:
            self._output.close_keep()
            if self._output.atomic:
                self._output.discard()
                kept = "the unfinished output was removed"
            else:
                until = format_clock(self.kept_until, self.zone)
                kept = f"{self.kept_messages} messages up to {until} kept in {self.path}"
        else:
            self._output.discard()
            kept = f"nothing was kept ({self.path} removed)"
        self.error = f"{what} {self.path} ({reason}); {kept}"


def recording_metadata(source: str, **extra: str) -> dict[str, str]:
    """Metadata for a new recording: source description plus anything else worth keeping."""
    out = {"source": source, "created": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
    out.update(extra)
    return out
