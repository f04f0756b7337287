"""The capture engine: a reader thread reads a source, decodes it and hands batches to sinks."""

from __future__ import annotations

import contextlib
import signal
import threading
import time
from collections import deque
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from types import FrameType
from typing import Any

from analyzer.errors import OutputError, SourceError
from analyzer.pipeline import Batch, Sink
from analyzer.protocol.types import TOPIC_DIAGNOSTICS, CanFrame, Event, StreamChunk
from analyzer.sources.base import link_event

# Bits of a CAN 2.0 frame without stuffing: SOF, arbitration, control, data, CRC, ACK, EOF
# and the 3-bit intermission. An extended frame with 8 data bytes is 131 bits, so a
# 1 Mbit/s bus is saturated at about 7,600 such frames per second.
CAN_BITS_EXTENDED = 67
CAN_BITS_STANDARD = 47
DEFAULT_BITRATE = 1_000_000

TICK_INTERVAL_S = 0.25  # how often the decoder is asked about stale partial messages
RATE_WINDOW_S = 1.0  # frames_per_s / bus_load_pct are averaged over this window
MAX_BATCH_ITEMS = 20_000  # a batch is handed over early when it grows this large
OUTPUT_CLOSED = "output closed"  # stop_reason when a printing sink's reader went away


class CaptureError(SourceError):
    """Why a capture stopped early (source failure, sink failure such as a full disk)."""


@dataclass(slots=True)
class CaptureStats:
    """Counters of a running capture (a snapshot is returned by ``Capture.stats``).

    ``bytes`` counts raw input bytes: stream bytes plus CAN data bytes. ``events`` counts
    decoded events, ``diagnostics`` the /diagnostics events among them (link changes
    included), by kind in ``diagnostic_kinds``. Rates are averaged over the last second.
    ``bus_load_pct`` estimates the load of the CAN bus (frame bit counts without stuffing,
    131 bits for an extended 8-byte frame) at the source's bitrate (1 Mbit/s by default).
    """

    frames: int = 0
    chunks: int = 0
    bytes: int = 0
    events: int = 0
    diagnostics: int = 0
    batches: int = 0
    frames_per_s: float = 0.0
    bytes_per_s: float = 0.0
    bus_load_pct: float = 0.0
    elapsed_s: float = 0.0
    diagnostic_kinds: dict[str, int] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def _default_decoder() -> Any:
    from analyzer.protocol.decoder import Decoder

    return Decoder()


def _reason(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror:
        where = f": {exc.filename}" if exc.filename else ""
        return f"{exc.strerror}{where}"
    lines = str(exc).strip().splitlines()
    return lines[0] if lines else exc.__class__.__name__


class Capture:
    """Reads ``source`` in a thread, decodes, and hands one Batch per ``batch_interval``
    to every sink's ``handle()`` (possibly empty, so sinks can flush on time).

    The decoder (a default ``Decoder()`` when None) gets every CAN frame / stream chunk;
    ``Event`` items of a source (link changes, pre-decoded file events) go straight into
    the batch. ``decoder.tick`` runs every 0.25 s on the source's clock, ``decoder.close``
    at the end. When the source ends, fails, ``stop()`` is called or a sink raises, the
    thread delivers a last batch to the sinks that still work, closes the source and
    closes every sink. Failures are kept in ``error`` (a CaptureError, one clear line);
    ``stop_reason`` says why it ended: "end of input", "stopped", "error", or "output
    closed" when a sink's reader went away (BrokenPipeError: a quiet stop, not an error).
    """

    def __init__(
        self,
        source: Any,
        sinks: Sequence[Sink],
        *,
        decoder: Any = None,
        batch_interval: float = 0.05,
    ) -> None:
        if batch_interval <= 0:
            raise ValueError("batch_interval must be positive")
        self.source = source
        self.sinks: list[Sink] = list(sinks)
        self.decoder = decoder if decoder is not None else _default_decoder()
        self.batch_interval = batch_interval
        self.bitrate: int = int(getattr(source, "bitrate", 0) or DEFAULT_BITRATE)
        self.error: CaptureError | None = None
        self.stop_reason: str = ""
        self._stats = CaptureStats()
        self._stats_lock = threading.Lock()  # snapshots copy the kinds dict while it grows
        self._bits = 0
        self._window: deque[tuple[float, int, int, int]] = deque()
        self._stop = threading.Event()
        self._done = threading.Event()
        self._failed_sinks: set[int] = set()
        self._notes: list[Event] = []
        self._thread: threading.Thread | None = None
        self._started_at = 0.0
        self._ended_at = 0.0  # when the reader stopped: elapsed time stops there
        self._last_item = (0.0, 0.0)  # (source time, monotonic time) of the newest item
        self._source_name = str(getattr(source, "source_name", "capture"))

    # -- control ---------------------------------------------------------------------------------

    def start(self) -> None:
        if self._thread is not None:
            raise RuntimeError("capture already started")
        self._started_at = time.monotonic()
        self._window.append((self._started_at, 0, 0, 0))
        self._thread = threading.Thread(target=self._run, name="capture", daemon=True)
        self._thread.start()

    def add_sink(self, sink: Sink) -> None:
        """Attach one more sink, before ``start()`` or while running (from the next batch on)."""
        self.sinks.append(sink)

    def stop(self) -> None:
        """Ask the reader thread to finish (returns at once; use join/wait to wait)."""
        self._stop.set()

    def join(self, timeout: float | None = None) -> bool:
        """Wait for the thread to finish; True when it has."""
        if self._thread is None:
            return True
        self._thread.join(timeout)
        return not self._thread.is_alive()

    def wait(self) -> None:
        """Block until the source ends, a failure stops it or ``stop()`` is called elsewhere."""
        if self._thread is None:
            return
        while not self._done.wait(0.2):
            pass
        self._thread.join()

    @property
    def running(self) -> bool:
        return self._thread is not None and not self._done.is_set()

    @property
    def stats(self) -> CaptureStats:
        with self._stats_lock:
            snapshot = CaptureStats(**self._stats.as_dict())
        if self._started_at:
            end = self._ended_at or time.monotonic()
            snapshot.elapsed_s = end - self._started_at
        return snapshot

    # -- the reader thread ------------------------------------------------------------------------

    def _run(self) -> None:
        batch = Batch()
        try:
            batch = self._loop(batch)
        except Exception as exc:  # a bug in a decoder or source: end cleanly, keep the reason
            self._fail(f"capture failed: {exc.__class__.__name__}: {exc}", exc)
        finally:
            self._finish(batch)

    def _loop(self, batch: Batch) -> Batch:
        interval = self.batch_interval
        now = time.monotonic()
        next_flush = now + interval
        next_tick = now + TICK_INTERVAL_S
        while not self._stop.is_set():
            wait = min(max(0.0, next_flush - time.monotonic()), interval)
            try:
                items = self.source.read(wait)
            except EOFError:
                self.stop_reason = "end of input"
                return batch
            except SourceError as exc:  # sources name themselves in their messages
                self._fail(_reason(exc), exc)
                return batch
            except Exception as exc:
                self._fail(f"{self._describe_source()} failed: {_reason(exc)}", exc)
                return batch
            if items:
                self._absorb(items, batch)
            now = time.monotonic()
            if now >= next_tick:
                next_tick = now + TICK_INTERVAL_S
                self._tick(batch, now)
            if now >= next_flush or len(batch.items) >= MAX_BATCH_ITEMS:
                self._deliver(batch)
                batch = Batch()
                next_flush = max(next_flush + interval, now)
        if not self.stop_reason:
            self.stop_reason = "stopped"
        return batch

    def _describe_source(self) -> str:
        return str(getattr(self.source, "description", "source"))

    def _absorb(self, items: list[Any], batch: Batch) -> None:
        stats = self._stats
        decoder = self.decoder
        raw = batch.items
        events = batch.events
        last: Any = None
        for item in items:
            if isinstance(item, CanFrame):
                raw.append(item)
                stats.frames += 1
                size = len(item.data)
                stats.bytes += size
                self._bits += (CAN_BITS_EXTENDED if item.extended else CAN_BITS_STANDARD) + 8 * size
                events.extend(decoder.feed_can(item))
                last = item
            elif isinstance(item, StreamChunk):
                raw.append(item)
                stats.chunks += 1
                stats.bytes += len(item.data)
                events.extend(decoder.feed_stream(item))
                last = item
            elif isinstance(item, Event):
                events.append(item)
        if last is not None:
            self._last_item = (last.time, time.monotonic())

    def _tick(self, batch: Batch, now: float) -> None:
        source_time, seen_at = self._last_item
        if seen_at:
            batch.events.extend(self.decoder.tick(source_time + (now - seen_at)))

    def _count(self, batch: Batch) -> None:
        with self._stats_lock:
            self._count_locked(batch)

    def _count_locked(self, batch: Batch) -> None:
        stats = self._stats
        for event in batch.events:
            if event.topic == TOPIC_DIAGNOSTICS:
                stats.diagnostics += 1
                kind = str(event.fields.get("kind", ""))
                stats.diagnostic_kinds[kind] = stats.diagnostic_kinds.get(kind, 0) + 1
            else:
                stats.events += 1
        stats.batches += 1
        now = time.monotonic()
        window = self._window
        window.append((now, stats.frames, self._bits, stats.bytes))
        while len(window) > 2 and now - window[1][0] >= RATE_WINDOW_S:
            window.popleft()
        t0, frames0, bits0, bytes0 = window[0]
        span = now - t0
        if span > 0:
            stats.frames_per_s = (stats.frames - frames0) / span
            stats.bytes_per_s = (stats.bytes - bytes0) / span
            stats.bus_load_pct = 100.0 * (self._bits - bits0) / span / self.bitrate

    def _deliver(self, batch: Batch) -> None:
        batch.wall_time = time.time()
        self._count(batch)
        for index, sink in enumerate(self.sinks):
            if index in self._failed_sinks:
                continue
            try:
                sink.handle(batch)
            except BrokenPipeError:
                # The reader of a printed output went away (| head): stop as asked.
                self._failed_sinks.add(index)
                self.stop_reason = OUTPUT_CLOSED
                self._stop.set()
            except OutputError as exc:  # says itself what could not be written
                self._failed_sinks.add(index)
                self._fail(str(exc), exc)
            except Exception as exc:
                self._failed_sinks.add(index)
                if isinstance(exc, SourceError):  # says what failed (disk full: cannot write...)
                    self._fail(_reason(exc), exc)
                else:
                    self._fail(f"{sink.__class__.__name__} failed: {_reason(exc)}", exc)

    def _fail(self, message: str, exc: BaseException | None) -> None:
        """Keep the first failure, stop the loop, and note it in the last batch."""
        if self.error is None:
            error = CaptureError(message)
            error.__cause__ = exc
            self.error = error
        self.stop_reason = "error"
        self._stop.set()
        self._notes.append(link_event(self._source_name, message, "failed"))

    def _finish(self, batch: Batch) -> None:
        self._ended_at = time.monotonic()
        try:
            with contextlib.suppress(Exception):
                self.source.close()
            try:
                batch.events.extend(self.decoder.close())
            except Exception as exc:
                self._fail(f"decoder failed at the end: {_reason(exc)}", exc)
            batch.events.extend(self._notes)
            self._notes.clear()
            self._deliver(batch)
            for index, sink in enumerate(self.sinks):
                try:
                    sink.close()
                except Exception as exc:
                    if index not in self._failed_sinks:
                        name = sink.__class__.__name__
                        self._fail(f"{name} failed while closing: {_reason(exc)}", exc)
        finally:
            self._done.set()


def run_until_interrupted(capture: Capture) -> int:
    """Run ``capture`` (starting it if needed) until its source ends or Ctrl-C / SIGTERM.

    The first Ctrl-C or SIGTERM stops the capture cleanly (sinks are closed, recordings
    finalised); a second Ctrl-C stops waiting (KeyboardInterrupt). Signal handlers are
    installed only in the main thread and restored afterwards. Returns 0, or 1 when the
    capture ended with an error (see ``capture.error``).
    """
    interrupted: list[int] = []

    def on_signal(signum: int, frame: FrameType | None) -> None:
        interrupted.append(signum)
        capture.stop()
        if signum == signal.SIGINT and len(interrupted) > 1:
            raise KeyboardInterrupt

    previous: dict[int, Any] = {}
    if threading.current_thread() is threading.main_thread():
        for signum in (int(signal.SIGINT), int(signal.SIGTERM)):
            previous[signum] = signal.signal(signum, on_signal)
    try:
        if capture._thread is None:
            capture.start()
        capture.wait()
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
    if interrupted and capture.error is None:
        capture.stop_reason = signal.Signals(interrupted[0]).name
    return 1 if capture.error is not None else 0
