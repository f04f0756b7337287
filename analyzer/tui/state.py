"""What the monitor screen shows, as plain data: folds capture batches, knows no UI and no clock.

Time comes only from the input: frame times, each batch's wall time, and the ``now``
given to :meth:`MonitorState.advance`. "Bus time" is the time axis of the frames (Unix
time for live sources, the log's times for a replay); between batches it runs on with
the wall clock, so the age of the last feedback keeps growing when the source goes quiet.
"""

from __future__ import annotations

from collections import Counter, deque

from analyzer.analysis.verdict_counts import VerdictCounts
from analyzer.bus_figures import BusFigures
from analyzer.link_status import LinkStatus
from analyzer.pipeline import Batch
from analyzer.protocol.ids import CAN_BITRATE
from analyzer.protocol.types import (
    BUS_ERROR,
    LINK,
    TOPIC_ANALYSIS_RESPONSE,
    TOPIC_CAN_OTHER,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_GIMBAL_RANGING,
    TOPIC_UAV_ALTITUDE,
    TOPIC_UAV_ATTITUDE,
    TOPIC_UAV_GPS,
    TOPIC_UAV_TEXT,
    CanFrame,
    Event,
)
from analyzer.tui.command_groups import command_group
from analyzer.tui.counters import Counters, count_items
from analyzer.tui.event_log import (
    COMMAND_VIEW_TOPICS,
    LOG_LIMIT,
    CommandRuns,
    LogEntry,
    insert_in_time_order,
)
from analyzer.tui.id_rows import (
    MAX_ROWS,
    IdRow,
    add_row,
    stream_key,
)
from analyzer.tui.rates import Meter
from analyzer.video.spec import is_camera_event

__all__ = ["FEEDBACK_STALE_S", "HISTORY", "HISTORY_STEP_S", "MonitorState"]

HISTORY = 60  # seconds of frames/s and errors/s kept for the sparklines
FEEDBACK_STALE_S = 1.0  # the gimbal answers about every 500 ms
HISTORY_STEP_S = 1.0  # the sparklines have a sample per second
FINDINGS_KEPT = 50  # the latest findings listed on the "Did it obey?" page


class MonitorState:
    """Everything on the monitor screen, updated by :meth:`fold` and :meth:`advance`."""

    def __init__(
        self,
        *,
        log_limit: int = LOG_LIMIT,
        history: int = HISTORY,
        feedback_stale_s: float = FEEDBACK_STALE_S,
        max_rows: int = MAX_ROWS,
    ) -> None:
        self.feedback_stale_s = feedback_stale_s
        self.max_rows = max_rows
        # gimbal
        self.attitude: Event | None = None
        self.ranging: Event | None = None
        self.last_feedback_time: float | None = None
        self.feedback_count = 0
        self.last_commands: dict[str, Event] = {}
        # response analysis: the latest finding and the verdicts so far
        self.finding: Event | None = None
        self.findings: deque[Event] = deque(maxlen=FINDINGS_KEPT)  # the latest, for page 5
        self.counts = VerdictCounts()  # as analyze counts: commands apart from the feedback
        self.verdicts: Counter[str] = self.counts.verdicts  # the commands' findings
        # UAV
        self.gps: Event | None = None
        self.altitude: Event | None = None
        self.uav_attitude: Event | None = None
        self.text: Event | None = None
        # logs
        self.seq = 0
        self.command_log: deque[LogEntry] = deque(maxlen=log_limit)
        self.all_log: deque[LogEntry] = deque(maxlen=log_limit)
        self._runs = CommandRuns()  # repeated commands folded in the command view
        # bus sniffer
        self.rows: dict[int | str, IdRow] = {}
        self.rows_added = 0  # bumps when a row appears, so views know to add it
        # counters: ``total`` never resets, ``counters`` is cleared by clear_counters()
        self.total = Counters()
        self.counters = Counters()
        self.cleared_at: float | None = None
        self.clear_count = 0
        self.dropped_batches = 0
        # link
        self.link_state = ""
        self.link_detail = ""
        self.link = LinkStatus()
        self.source_ended = False
        self.bus = BusFigures()  # the CAN controllers' error frames: state, worst, classes
        # rates from the messages' own times (rates.Meter), a sample a second for the graphs
        self._frames_meter = Meter()  # frames and stream chunks
        self._bits_meter = Meter()
        self._errors_meter = Meter()
        self._feedback_meter = Meter()  # attitude and ranging: the gimbal's answers
        self._topic_meters: dict[str, Meter] = {}
        self.frames_history: deque[float] = deque([0.0] * history, maxlen=history)
        self.errors_history: deque[float] = deque([0.0] * history, maxlen=history)
        self._window_start: float | None = None
        self._window_frames = 0
        self._window_bits = 0
        self._window_errors = 0
        # clock
        self.last_item_time: float | None = None
        self._offset = 0.0  # bus time minus wall time at the last batch with items
        self.now = 0.0  # current bus time
        self.version = 0  # bumps on every change

    # -- input -------------------------------------------------------------------------------

    def fold(self, batch: Batch, wall_time: float | None = None) -> None:
        """Take in one batch from the capture."""
        wall = batch.wall_time if wall_time is None else wall_time
        self.version += 1
        if batch.items:
            self._fold_items(batch)
            last = self.last_item_time
            if last is not None:
                self._offset = last - wall
                self.now = last  # the frames define the time axis (a replay may start anew)
        else:
            self._fold_events(batch.events)
        self.advance(wall)

    def advance(self, wall_now: float) -> None:
        """Let time pass: ages grow, rates fall in a silence (``rates.Meter``).

        While frames flow, the sparklines' seconds are closed by the frames' own times (so
        the capture's batching delay does not skew them); the clock closes them only in
        silence.
        """
        now = wall_now + self._offset
        last = self.last_item_time
        if last is not None and now < last:
            now = last
        if now > self.now:
            self.now = now
        if last is None or now - last >= HISTORY_STEP_S:
            self._advance_to(now)

    def mark_dropped(self, batches: int) -> None:
        """The display could not keep up and skipped batches (the capture itself lost nothing)."""
        self.dropped_batches += batches
        self.version += 1

    def source_finished(self) -> None:
        self.source_ended = True
        self.version += 1

    def clear_counters(self) -> None:
        """The user's explicit reset of counters and per-ID counts (totals since start stay)."""
        self.counters = Counters()
        for row in self.rows.values():
            row.count = 0
            row.meter.clear()
        self.cleared_at = self.now
        self.clear_count += 1
        self.version += 1

    # -- derived -------------------------------------------------------------------------------

    @property
    def feedback_age(self) -> float | None:
        if self.last_feedback_time is None:
            return None
        return max(self.now - self.last_feedback_time, 0.0)

    @property
    def feedback_stale(self) -> bool:
        age = self.feedback_age
        return age is None or age > self.feedback_stale_s

    @property
    def bus_load(self) -> float:
        """Share of a 1 Mbit/s CAN bus used, 0..1+ (stuff bits not counted)."""
        return self.bits_per_s / CAN_BITRATE

    @property
    def items_counted(self) -> str:
        """What the source delivers: CAN "frames", "chunks" of a stream (TCP, UART), or
        "frames and chunks" (a proxy next to a bus); "frames" before anything came."""
        frames, chunks = self.total.frames, self.total.chunks
        if chunks and not frames:
            return "chunks"
        return "frames and chunks" if chunks else "frames"

    @property
    def frames_per_s(self) -> float:
        """CAN frames and stream chunks per second."""
        return self._frames_meter.rate(self.now)

    @property
    def bits_per_s(self) -> float:
        return self._bits_meter.rate(self.now)

    @property
    def errors_per_s(self) -> float:
        return self._errors_meter.rate(self.now)

    @property
    def feedback_rate(self) -> float:
        """Feedback messages (attitude and ranging) per second."""
        return self._feedback_meter.rate(self.now)

    @property
    def topic_rates(self) -> dict[str, float]:
        """Events per second of each topic seen."""
        return {topic: meter.rate(self.now) for topic, meter in self._topic_meters.items()}

    def row_rate(self, row: IdRow) -> float:
        """Frames (or chunks) per second of one row of the ID table."""
        return row.meter.rate(self.now)

    def age(self, event: Event | None) -> float | None:
        return None if event is None else max(self.now - event.time, 0.0)

    # -- folding -------------------------------------------------------------------------------

    def _fold_items(self, batch: Batch) -> None:
        """Items in order; the batch's events are folded in step, so each lands in its window."""
        events = batch.events
        n_events = len(events)
        next_event = 0
        rows = self.rows
        window_end = None if self._window_start is None else self._window_start + HISTORY_STEP_S
        frames = chunks = nbytes = bits = 0
        last_time = self.last_item_time
        for item in batch.items:
            t = item.time
            if window_end is None or t >= window_end or t < window_end - 2 * HISTORY_STEP_S:
                first = next_event
                while next_event < n_events and events[next_event].time < t:
                    next_event += 1
                if next_event > first:
                    self._fold_events(events[first:next_event])
                self._count(last_time, frames, chunks, nbytes, bits)
                frames = chunks = nbytes = bits = 0
                self._advance_to(t)
                window_end = (self._window_start or t) + HISTORY_STEP_S
            data = item.data
            if isinstance(item, CanFrame):
                frames += 1
                bits += (67 if item.extended else 47) + 8 * len(data)
                key: int | str = item.can_id
                row = rows.get(key)
                if row is None:
                    row = self._new_row(key, item)
            else:
                chunks += 1
                key = stream_key(item)
                row = rows.get(key)
                if row is None:
                    row = self._new_row(key, None)
            nbytes += len(data)
            row.count += 1
            row.meter.add(t)
            if data != row.data:
                row.note_data(data, t)
            row.last_time = t
            last_time = t
        self._count(last_time, frames, chunks, nbytes, bits)
        self.last_item_time = last_time
        if next_event < n_events:
            self._fold_events(events[next_event:])

    def _count(self, t: float | None, frames: int, chunks: int, nbytes: int, bits: int) -> None:
        """Items read up to ``t``: into the counters, the rates and the second's sample."""
        if frames or chunks:
            self._window_frames += frames + chunks
            self._window_bits += bits
            count_items(self.total, self.counters, frames, chunks, nbytes)
            if t is not None:
                self._frames_meter.add(t, frames + chunks)
                self._bits_meter.add(t, bits)

    def _new_row(self, key: int | str, frame: CanFrame | None) -> IdRow:
        row, added = add_row(self.rows, key, frame, self.max_rows)
        if added:
            self.rows_added += 1
        return row

    def _fold_events(self, events: list[Event]) -> None:
        total = self.total
        counters = self.counters
        for event in events:
            topic = event.topic
            if topic == TOPIC_CAN_OTHER:
                continue
            total.events += 1
            counters.events += 1
            meter = self._topic_meters.get(topic)
            if meter is None:
                meter = self._topic_meters[topic] = Meter()
            meter.add(event.time)
            if event.warnings:
                total.warnings += 1
                counters.warnings += 1
            self._log(event)
            if topic == TOPIC_DIAGNOSTICS:
                self._fold_diagnostic(event)
            else:
                self._fold_latest(event)

    def _log(self, event: Event) -> None:
        """Into the log of everything and, for a command or finding, the command view's
        (a command repeated folds into its line there)."""
        self.seq += 1
        insert_in_time_order(self.all_log, LogEntry(self.seq, event))
        topic = event.topic
        if topic in COMMAND_VIEW_TOPICS:
            entry = LogEntry(self.seq, event)  # its own: a folded line changes
            if topic != TOPIC_COMMAND or not self._runs.fold(entry):
                insert_in_time_order(self.command_log, entry)

    def _fold_latest(self, event: Event) -> None:
        """The newest event of each topic the panels show."""
        topic = event.topic
        if topic == TOPIC_GIMBAL_ATTITUDE:
            self.attitude = event
            self._note_feedback(event)
        elif topic == TOPIC_COMMAND:
            self.last_commands[command_group(event)] = event
        elif topic == TOPIC_UAV_GPS:
            self.gps = event
        elif topic == TOPIC_UAV_ALTITUDE:
            self.altitude = event
        elif topic == TOPIC_UAV_ATTITUDE:
            self.uav_attitude = event
        elif topic == TOPIC_UAV_TEXT:
            self.text = event
        elif topic == TOPIC_GIMBAL_RANGING:
            self.ranging = event
            self._note_feedback(event)
        elif topic == TOPIC_ANALYSIS_RESPONSE:
            self.finding = event
            self.findings.append(event)
            self.counts.add(event.fields)

    def _fold_diagnostic(self, event: Event) -> None:
        """A diagnostic: counted by kind; a link change for the status bar, else an error."""
        kind = str(event.fields.get("kind", "?"))
        self.total.kinds[kind] += 1
        self.counters.kinds[kind] += 1
        if kind == LINK:
            if not is_camera_event(event):  # the status bar is the telemetry's link
                self.link.note(event)
                self.link_state = self.link.state
                self.link_detail = self.link.detail
            return
        self._window_errors += 1
        self._errors_meter.add(event.time)
        if kind == BUS_ERROR:
            self.bus.add_events((event,))

    def _note_feedback(self, event: Event) -> None:
        self.feedback_count += 1
        self._feedback_meter.add(event.time)
        if self.last_feedback_time is None or event.time >= self.last_feedback_time:
            self.last_feedback_time = event.time

    # -- time --------------------------------------------------------------------------------

    def _advance_to(self, now: float) -> None:
        """Move bus time to ``now``, closing the sparklines' seconds that ended on the way."""
        start = self._window_start
        if start is None or now < start:
            # first data, or time went backwards (a new log): restart the windows
            self._window_start = now
            self.now = now
            return
        if now > self.now:
            self.now = now
        elapsed = now - start
        if elapsed < HISTORY_STEP_S:
            return
        # after a long silence the window's frames are taken to fill its first second
        span = max(elapsed if elapsed < 2 * HISTORY_STEP_S else HISTORY_STEP_S, 1e-9)
        self.frames_history.append(self._window_frames / span)
        self.errors_history.append(self._window_errors / span)
        self._window_frames = self._window_bits = self._window_errors = 0
        # whole seconds of silence after the window: zero samples (bounded by the history)
        silent = int(elapsed // HISTORY_STEP_S) - 1
        for _ in range(min(silent, self.frames_history.maxlen or 0)):
            self.frames_history.append(0.0)
            self.errors_history.append(0.0)
        self._window_start = now
