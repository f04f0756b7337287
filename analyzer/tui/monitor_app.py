"""The monitor app: folds batches from the bridge into the state, redraws at a fixed rate."""

from __future__ import annotations

import asyncio
import contextlib
import os
import signal
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar, Protocol

from textual import events
from textual.app import App, ComposeResult
from textual.binding import BindingType
from textual.geometry import Size
from textual.message import Message
from textual.screen import Screen
from textual.widgets import DataTable

from analyzer.portable import STOP_SIGNALS
from analyzer.timefmt import UTC, TimeZone
from analyzer.tui.bridge import TuiBridge
from analyzer.tui.command_log import CommandLog
from analyzer.tui.detail_screen import DetailScreen
from analyzer.tui.diagnostics_panel import DiagnosticsPanel
from analyzer.tui.event_filter import EventFilter
from analyzer.tui.event_log import LogEntry
from analyzer.tui.gimbal_panel import GimbalPanel
from analyzer.tui.help_screen import HelpScreen
from analyzer.tui.id_table import IdTable
from analyzer.tui.monitor_keys import MONITOR_BINDINGS
from analyzer.tui.monitor_layout import (
    HORIZONTAL_BREAKPOINTS,
    MONITOR_CSS,
    PAGES,
    VERTICAL_BREAKPOINTS,
    compose_monitor,
    is_paged,
)
from analyzer.tui.prompt_bar import PromptBar
from analyzer.tui.response_panel import ResponsePanel
from analyzer.tui.state import MonitorState
from analyzer.tui.status_bar import StatusBar, StatusInfo
from analyzer.tui.uav_panel import UavPanel

REFRESH_HZ = 8.0  # screen updates per second, whatever the input rate


class CaptureControl(Protocol):
    """What the app needs of a capture: to stop it and wait for its sinks to finish."""

    def stop(self) -> None: ...

    def join(self, timeout: float | None = None) -> object: ...


class BatchesReady(Message):
    """Posted (from the capture thread, via the bridge) when batches wait in the bridge."""


@dataclass
class RefreshStats:
    """How the display keeps up (read by tests and the load benchmark)."""

    batches: int = 0
    messages: int = 0
    refreshes: int = 0
    last_batch_wall: float = 0.0
    lag: float = 0.0  # at the last refresh: now - capture time of the newest batch shown
    max_lag: float = 0.0


def _file_size(path: str) -> int | None:
    try:
        return os.path.getsize(path)
    except OSError:
        return None


class MonitorApp(App[int]):
    """The live monitor. Feed it through ``bridge`` (a Sink given to the capture)."""

    TITLE = "gimbal-analyzer monitor"
    ENABLE_COMMAND_PALETTE = False

    # Textual sets these classes on the screen from its size; MONITOR_CSS uses them
    HORIZONTAL_BREAKPOINTS = HORIZONTAL_BREAKPOINTS
    VERTICAL_BREAKPOINTS = VERTICAL_BREAKPOINTS

    CSS = MONITOR_CSS

    BINDINGS: ClassVar[list[BindingType]] = MONITOR_BINDINGS

    def __init__(
        self,
        bridge: TuiBridge,
        *,
        source_label: str = "",
        recording: str | None = None,
        capture: CaptureControl | None = None,
        clock: Callable[[], float] = time.time,
        refresh_hz: float = REFRESH_HZ,
        state: MonitorState | None = None,
        file_size: Callable[[str], int | None] = _file_size,
        handle_sigterm: bool = False,
        exit_when_done: bool = False,
        live_status: Callable[[], tuple[str, bool]] | None = None,
        zone: TimeZone = UTC,
    ) -> None:
        super().__init__()
        self.zone = zone  # every time on the screen (UTC, or local with --local-time)
        self.live_status = live_status  # the live Foxglove server's words, and whether to alert
        self.bridge = bridge
        self.capture = capture
        self.clock = clock
        self.refresh_hz = refresh_hz
        self.state = state or MonitorState()
        self.file_size = file_size
        self.info = StatusInfo(source=source_label, recording=recording, zone=zone)
        self.filter = EventFilter()
        self.search_text = ""
        self.paused = False
        self.stats = RefreshStats()
        self._paused_seq = 0
        self._log_key: tuple[object, ...] = ()
        self._capture_stopped = False
        self._handle_sigterm = handle_sigterm
        self._signal_handlers: dict[int, signal.Handlers | Callable[..., object] | int | None] = {}
        self.exit_when_done = exit_when_done  # quit once the source has ended and is shown
        self._mounted = False
        self.page = "state"

    # -- layout --------------------------------------------------------------------------------

    def compose(self) -> ComposeResult:
        yield from compose_monitor(self.zone)

    def on_mount(self) -> None:
        if self._handle_sigterm:
            # SIGTERM (Windows: Ctrl-Break, the console closed) quits like q does, so the
            # recording is finalised
            for signum in STOP_SIGNALS:
                try:
                    asyncio.get_running_loop().add_signal_handler(
                        signum, lambda: self.call_later(self.action_quit)
                    )
                except NotImplementedError:  # Windows' event loops: a plain handler
                    self._signal_handlers[signum] = signal.signal(
                        signum, lambda *_: self.call_later(self.action_quit)
                    )
                except (RuntimeError, ValueError):  # not the main thread
                    pass
        # widgets of the main screen, kept so redraws work while a pop-up screen is shown
        self._status = self.query_one(StatusBar)
        self._gimbal = self.query_one(GimbalPanel)
        self._uav = self.query_one(UavPanel)
        self._response = self.query_one(ResponsePanel)
        self._log_view = self.query_one(CommandLog)
        self._ids = self.query_one(IdTable)
        self._diagnostics = self.query_one(DiagnosticsPanel)
        self._prompt = self.query_one(PromptBar)
        self._main_screen: Screen[object] = self.screen
        self._mounted = True
        self.apply_layout()
        self.bridge.connect(self._wake)
        self.set_interval(1.0 / self.refresh_hz, self.refresh_view)
        self._log_view.focus()
        self.refresh_view()

    @property
    def paged(self) -> bool:
        """Whether the screen shows one page at a time (the terminal is too small for all)."""
        return self.main_screen.has_class("-paged")

    @property
    def main_screen(self) -> Screen[object]:
        return self._main_screen if self._mounted else self.screen

    def apply_layout(self, size: Size | None = None) -> None:
        """All-in-one or one page at a time, for the terminal's size."""
        width, height = size or self.size
        screen = self.main_screen
        paged = is_paged(width, height)
        screen.set_class(paged, "-paged")
        for page, _ in PAGES.values():
            screen.set_class(page == self.page, f"-page-{page}")
        # its own page lists the findings before the latest too
        self._response.earlier = paged and self.page == "response"
        self.refresh_bindings()

    def on_resize(self, event: events.Resize) -> None:
        # the new size, already known here while the screen is still being resized
        if self._mounted:
            self.apply_layout(event.size)

    def action_page(self, page: str) -> None:
        """Show one page (on a small terminal); the state behind it is shared by all pages."""
        self.page = page
        self.apply_layout()
        if page == "ids":
            self._ids.focus()
        elif page in ("state", "log"):
            self._log_view.focus()
        self._force_redraw()

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action == "page":
            # the keys (and their footer entries) exist only when there are pages
            return self.paged
        return True

    def on_unmount(self) -> None:
        self._mounted = False
        self.bridge.disconnect()
        if self._handle_sigterm:
            for signum in STOP_SIGNALS:
                if signum in self._signal_handlers:
                    signal.signal(signum, self._signal_handlers.pop(signum))
                    continue
                with contextlib.suppress(NotImplementedError, RuntimeError, ValueError):
                    asyncio.get_running_loop().remove_signal_handler(signum)

    # -- data in -------------------------------------------------------------------------------

    def _wake(self) -> None:
        """Runs in the capture thread: one message per wake-up (post_message is thread-safe)."""
        self.post_message(BatchesReady())

    def on_batches_ready(self, message: BatchesReady) -> None:
        self.stats.messages += 1
        self.pull()

    def pull(self) -> int:
        """Fold every batch waiting in the bridge into the state (cheap; no drawing)."""
        batches, dropped = self.bridge.take()
        state = self.state
        for batch in batches:
            wall = batch.wall_time or self.clock()
            state.fold(batch, wall)
            self.stats.last_batch_wall = wall
        self.stats.batches += len(batches)
        if dropped:
            state.mark_dropped(dropped)
        if self.bridge.closed and not state.source_ended and not self.bridge.backlog:
            state.source_finished()
            if self.exit_when_done:
                self.exit(0)
        return len(batches)

    # -- drawing -------------------------------------------------------------------------------

    def refresh_view(self) -> None:
        """Redraw from the state (timer-driven, so the cost does not grow with the input rate)."""
        if not self._mounted:
            return
        now = self.clock()
        state = self.state
        state.advance(now)
        info = self.info
        if info.recording:
            info.recording_size = self.file_size(info.recording)
        source = getattr(self.capture, "source", None)
        info.dropped = int(getattr(source, "dropped_items", 0) or 0)
        if self.live_status is not None:
            info.live, info.live_alert = self.live_status()
        info.paused = self.paused
        info.paused_new = state.seq - self._paused_seq if self.paused else 0
        info.filter_text = self.filter.text
        self._status.show_status(state, info)
        if self.paused:
            return
        self.stats.refreshes += 1
        if self.stats.last_batch_wall:
            self.stats.lag = max(now - self.stats.last_batch_wall, 0.0)
            self.stats.max_lag = max(self.stats.max_lag, self.stats.lag)
        self._show_top(state)
        self._response.show(state)
        self._show_log()
        self._ids.show(state, self.filter)
        self._diagnostics.show(state)

    def _show_top(self, state: MonitorState) -> None:
        """Gimbal and UAV panels; side by side they are made equally tall."""
        gimbal, uav = self._gimbal, self._uav
        side_by_side = gimbal.region.y == uav.region.y
        rows = max(gimbal.rows_at(gimbal.size.width), uav.rows_at(uav.size.width))
        gimbal.min_rows = uav.min_rows = rows if side_by_side else 0
        gimbal.show(state)
        uav.show(state)

    def _show_log(self) -> None:
        log = self._log_view
        source = self.state.command_log if self.info.view == "commands" else self.state.all_log
        key = (self.state.seq, self.info.view, self.filter.text, log.raw, log.search)
        if key == self._log_key:
            return
        self._log_key = key
        if self.filter.active:
            flt = self.filter
            entries = [e for e in source if flt.matches_event(e.event, log.text_of(e))]
        else:
            entries = list(source)
        log.set_entries(entries)
        what = "commands + diagnostics" if self.info.view == "commands" else "all topics"
        log.border_title = f"Log: {what}"
        log.border_subtitle = f"{len(entries)} of {len(source)}" if self.filter.active else ""

    # -- actions -------------------------------------------------------------------------------

    def action_toggle_pause(self) -> None:
        self.paused = not self.paused
        if self.paused:
            self._paused_seq = self.state.seq
        self.refresh_view()

    def action_filter(self) -> None:
        self._prompt.open("filter", self.filter.text)

    def action_search(self) -> None:
        self._prompt.open("search", self.search_text)

    def on_prompt_bar_done(self, message: PromptBar.Done) -> None:
        log = self._log_view
        log.focus()
        if message.value is None:
            return
        if message.mode == "filter":
            self.set_filter(message.value)
        elif message.mode == "search":
            self.search_text = message.value.strip()
            log.search = self.search_text
            self._log_key = ()
            if self.search_text and not log.find(self.search_text):
                self.notify(f"not found: {self.search_text}", severity="warning", timeout=2)
            log.refresh()

    def set_filter(self, text: str) -> None:
        self.filter = EventFilter.parse(text)
        self._force_redraw()

    def action_find_next(self) -> None:
        self._log_view.find(self.search_text, backwards=True)

    def action_find_previous(self) -> None:
        self._log_view.find(self.search_text, backwards=False)

    def action_clear_counters(self) -> None:
        self.state.clear_counters()
        self.notify("counters cleared", timeout=1.5)
        self._force_redraw()

    def action_toggle_raw(self) -> None:
        log = self._log_view
        log.raw = not log.raw
        self.info.raw = log.raw
        self._force_redraw()

    def action_toggle_view(self) -> None:
        self.info.view = "all" if self.info.view == "commands" else "commands"
        self._force_redraw()

    def action_follow(self) -> None:
        self._log_view.action_follow()

    def action_help(self) -> None:
        self.push_screen(HelpScreen())

    def on_command_log_selected(self, message: CommandLog.Selected) -> None:
        self.show_detail(message.entry)

    def show_detail(self, entry: LogEntry) -> None:
        self.push_screen(DetailScreen(entry.event, entry, self.zone))

    def on_data_table_row_selected(self, message: DataTable.RowSelected) -> None:
        """Enter on an ID row: filter the log by that ID (a second Enter clears it)."""
        key = str(message.row_key.value or "")
        if key.startswith("0x"):
            self.set_filter("" if self.filter.text == key else key)

    def _force_redraw(self) -> None:
        self._log_key = ()
        if self.paused:
            # the user changed the view: show it, but keep the display frozen otherwise
            self.paused = False
            self.refresh_view()
            self.paused = True
            self._status.show_status(self.state, self.info)
        else:
            self.refresh_view()

    async def action_quit(self) -> None:
        """Stop the capture (its sinks finalise the recording), then leave."""
        if self.capture is not None and not self._capture_stopped:
            what = "finalising the recording" if self.info.recording else "stopping the capture"
            self.notify(f"{what}…", timeout=10)
        await asyncio.to_thread(self.stop_capture)
        self.exit(0)

    def stop_capture(self) -> None:
        if self._capture_stopped or self.capture is None:
            return
        self._capture_stopped = True
        self.capture.stop()
        self.capture.join()
