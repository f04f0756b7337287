"""The command log: decoded events in plain words, newest at the bottom, drawn line by line.

A line-API widget: it keeps a reference to the (bounded, filtered) entry list and renders
only the rows on screen, so a long log costs nothing until it is looked at. With no
cursor it follows the newest entry; moving the cursor stops following until End.
"""

from __future__ import annotations

from typing import ClassVar

from rich.style import Style
from rich.text import Text
from textual.binding import Binding, BindingType
from textual.geometry import Size
from textual.message import Message
from textual.scroll_view import ScrollView
from textual.strip import Strip

from analyzer.protocol.types import LINK, TOPIC_COMMAND, TOPIC_DIAGNOSTICS
from analyzer.timefmt import UTC, TimeZone
from analyzer.tui.event_log import LogEntry
from analyzer.tui.formatting import event_raw, event_text, folded_text, format_time

RAW_WIDTH = 24  # "0F 04 0C FE 00 00 00 00" + a space
TEXT_CACHE_LIMIT = 10_000

_DIAGNOSTIC = Style(color="red")
_WARNING = Style(color="yellow")
_OTHER = Style(dim=True)
_TIME = Style(dim=True)
_RAW = Style(color="cyan")
_CURSOR = Style(reverse=True)
_MATCH = Style(bgcolor="magenta", color="white", bold=True)


class CommandLog(ScrollView, can_focus=True):
    """Scrollable, selectable view of log entries."""

    DEFAULT_CSS = """
    CommandLog { border: round $primary; height: 1fr; }
    CommandLog:focus { border: round $accent; }
    """

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("up", "cursor_up", "Up", show=False),
        Binding("down", "cursor_down", "Down", show=False),
        Binding("pageup", "page_up_cursor", "Page up", show=False),
        Binding("pagedown", "page_down_cursor", "Page down", show=False),
        Binding("home", "first", "First", show=False),
        Binding("end", "follow", "Follow", show=False),
        Binding("enter", "select", "Details"),
    ]

    class Selected(Message):
        """The user asked for the details of an entry."""

        def __init__(self, entry: LogEntry) -> None:
            super().__init__()
            self.entry = entry

    def __init__(self, *, id: str | None = None, zone: TimeZone = UTC) -> None:
        super().__init__(id=id)
        self.zone = zone  # the times and the moments among the values
        self.entries: list[LogEntry] = []
        self._index: dict[int, int] = {}  # seq -> position in entries
        self.cursor_seq: int | None = None
        self.raw = False
        self.search = ""
        self._texts: dict[tuple[int, int], str] = {}

    # -- content -------------------------------------------------------------------------------

    def set_entries(self, entries: list[LogEntry]) -> None:
        """Show these entries (oldest first); keeps the cursor on its entry if still there."""
        self.entries = entries
        self._index = {e.seq: i for i, e in enumerate(entries)}
        if len(self._texts) > TEXT_CACHE_LIMIT:
            self._texts.clear()
        self.virtual_size = Size(0, len(entries))
        if self.cursor_seq is None:
            self.scroll_end(animate=False, immediate=True, x_axis=False, force=True)
        self.refresh()

    def text_of(self, entry: LogEntry) -> str:
        """The plain words of an entry (cached: events do not change; a folded line of
        repeated commands is worded again when it grows)."""
        key = (entry.seq, entry.count)
        text = self._texts.get(key)
        if text is None:
            text = event_text(entry.event, self.zone)
            if entry.count > 1:
                name = str(entry.event.fields.get("name", ""))
                text = folded_text(text, name, entry.count, entry.event.time - entry.start)
            self._texts[key] = text
        return text

    def line_of(self, entry: LogEntry) -> Text:
        """One log line: time, raw bytes when the raw view is on, words; styled by kind."""
        event = entry.event
        line = Text(no_wrap=True, end="")
        line.append(format_time(entry.start, self.zone), _TIME)
        line.append("  ")
        if self.raw:
            raw = event_raw(event)
            line.append(f"{raw or '—':<{RAW_WIDTH}}", _RAW)
        style: Style | None = None
        if event.topic == TOPIC_DIAGNOSTICS:
            style = _WARNING if event.fields.get("kind") == LINK else _DIAGNOSTIC
        elif event.warnings:
            style = _WARNING
        elif event.topic != TOPIC_COMMAND:
            style = _OTHER
        line.append(self.text_of(entry), style)
        if event.warnings:
            line.append(f"  ⚠ {event.warnings[0]}", _WARNING)
        if self.search:
            line.highlight_words([self.search], _MATCH, case_sensitive=False)
        return line

    def visible_lines(self) -> list[str]:
        """Plain text of the rows on screen, in full (for tests and text snapshots)."""
        top = self.scroll_offset.y
        return [self.line_of(e).plain for e in self.entries[top : top + self.size.height]]

    # -- rendering -----------------------------------------------------------------------------

    def render_line(self, y: int) -> Strip:
        scroll_x, scroll_y = self.scroll_offset
        index = scroll_y + y
        width = self.size.width
        rich_style = self.rich_style
        if index >= len(self.entries):
            return Strip.blank(width, rich_style)
        entry = self.entries[index]
        text = self.line_of(entry)
        shown = self.scrollable_content_region.width  # the scrollbar takes the rest
        if text.cell_len > shown:  # cut: it says so, and Enter shows the whole of it
            text.truncate(shown, overflow="ellipsis")
        if entry.seq == self.cursor_seq:
            text.stylize(_CURSOR)
        strip = Strip(text.render(self.app.console), text.cell_len)
        return strip.crop_extend(scroll_x, scroll_x + width, rich_style).apply_style(rich_style)

    # -- cursor --------------------------------------------------------------------------------

    @property
    def cursor_index(self) -> int | None:
        if self.cursor_seq is None or not self.entries:
            return None
        # an entry that has left the bounded log: the cursor stays at the top
        return self._index.get(self.cursor_seq, 0)

    @property
    def selected(self) -> LogEntry | None:
        """The entry under the cursor, or the newest one when following."""
        if not self.entries:
            return None
        index = self.cursor_index
        return self.entries[-1 if index is None else index]

    def _move(self, index: int) -> None:
        if not self.entries:
            return
        index = max(0, min(index, len(self.entries) - 1))
        self.cursor_seq = self.entries[index].seq
        top = self.scroll_offset.y
        height = max(self.size.height, 1)
        if index < top:
            self.scroll_to(y=index, animate=False, immediate=True, force=True)
        elif index >= top + height:
            self.scroll_to(y=index - height + 1, animate=False, immediate=True, force=True)
        self.refresh()

    def move_to_seq(self, seq: int) -> None:
        if seq in self._index:
            self._move(self._index[seq])

    def action_cursor_up(self) -> None:
        index = self.cursor_index
        self._move(len(self.entries) - 1 if index is None else index - 1)

    def action_cursor_down(self) -> None:
        index = self.cursor_index
        if index is None:
            return
        if index >= len(self.entries) - 1:
            self.action_follow()
        else:
            self._move(index + 1)

    def action_page_up_cursor(self) -> None:
        index = self.cursor_index
        self._move((len(self.entries) if index is None else index) - max(self.size.height, 1))

    def action_page_down_cursor(self) -> None:
        index = self.cursor_index
        if index is not None:
            self._move(index + max(self.size.height, 1))

    def action_first(self) -> None:
        self._move(0)

    def action_follow(self) -> None:
        """Back to following the newest entry."""
        self.cursor_seq = None
        self.scroll_end(animate=False, immediate=True, x_axis=False, force=True)
        self.refresh()

    def action_select(self) -> None:
        entry = self.selected
        if entry is not None:
            self.post_message(self.Selected(entry))

    def find(self, text: str, *, backwards: bool = True) -> bool:
        """Move the cursor to the next entry (older when ``backwards``) containing ``text``."""
        if not text or not self.entries:
            return False
        needle = text.lower()
        index = self.cursor_index
        n = len(self.entries)
        start = (n if index is None else index) if backwards else (-1 if index is None else index)
        step = -1 if backwards else 1
        i = start + step
        while 0 <= i < n:
            entry = self.entries[i]
            if needle in self.text_of(entry).lower() or needle in event_raw(entry.event).lower():
                self._move(i)
                return True
            i += step
        return False
