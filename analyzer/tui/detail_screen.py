"""A pop-up with every field, every warning and the raw bytes of one event: the whole of a
log line the screen cut."""

from __future__ import annotations

import json
from typing import ClassVar

from rich.table import Table
from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import VerticalScroll
from textual.screen import ModalScreen
from textual.widgets import Static

from analyzer.protocol.types import Event
from analyzer.timefmt import UTC, TimeZone
from analyzer.tui.event_log import LogEntry
from analyzer.tui.formatting import event_raw, event_text, format_time


def render_detail(event: Event, entry: LogEntry | None = None, zone: TimeZone = UTC) -> Table:
    """Every field of ``event``, its times in ``zone``; with the log ``entry`` of a folded
    line, how many commands it stands for (the last one's fields are shown)."""
    table = Table.grid(padding=(0, 2))
    table.add_column(style="dim", no_wrap=True)
    table.add_column()
    table.add_row("event", Text(event_text(event, zone), style="bold"))
    if entry is not None and entry.count > 1:
        start, end = format_time(entry.start, zone), format_time(event.time, zone)
        span = f"{start.strip()} to {end.strip()}"
        table.add_row("repeated", f"{entry.count} times from {span}; the last one below")
    table.add_row("topic", event.topic)
    table.add_row("time", f"{format_time(event.time, zone)}  ({event.time:.6f})")
    table.add_row("source", event.source or "—")
    for key, value in event.fields.items():
        shown = value if isinstance(value, str) else json.dumps(value, default=str)
        table.add_row(key, Text(shown, style="cyan" if key == "raw" else ""))
    raw = event_raw(event)
    table.add_row("raw bytes", Text(raw or "— (not carried by this event)", style="bold cyan"))
    if event.warnings:
        for warning in event.warnings:
            table.add_row("warning", Text(warning, style="yellow"))
    else:
        table.add_row("warnings", Text("none", style="dim"))
    return table


class DetailScreen(ModalScreen[None]):
    """Shows one event; Escape or Enter closes it."""

    DEFAULT_CSS = """
    DetailScreen { align: center middle; }
    DetailScreen > VerticalScroll {
        width: 100%; max-width: 90; max-height: 100%;
        border: thick $accent; background: $surface; padding: 0 1;
    }
    """

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("escape", "close", "Close"),
        Binding("enter", "close", "Close", show=False),
        Binding("q", "close", "Close", show=False),
    ]

    def __init__(self, event: Event, entry: LogEntry | None = None, zone: TimeZone = UTC) -> None:
        super().__init__()
        self.event = event
        self.entry = entry
        self.zone = zone

    def compose(self) -> ComposeResult:
        with VerticalScroll() as scroll:
            scroll.border_title = "Event details"
            yield Static(render_detail(self.event, self.entry, self.zone), id="detail")

    def action_close(self) -> None:
        self.dismiss(None)
