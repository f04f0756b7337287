"""The monitor's keys: the action each runs and its name in the footer (? shows them all)."""

from __future__ import annotations

from textual.binding import Binding, BindingType

from analyzer.tui.monitor_layout import PAGES

MONITOR_BINDINGS: list[BindingType] = [
    *(Binding(key, f"page('{page}')", name) for key, (page, name) in PAGES.items()),
    Binding("q", "quit", "Quit"),
    Binding("ctrl+c", "quit", "Quit", show=False, priority=True),
    Binding("p", "toggle_pause", "Pause"),
    Binding("space", "toggle_pause", "Pause", show=False),
    Binding("f", "filter", "Filter"),
    Binding("slash", "search", "Search", key_display="/"),
    Binding("n", "find_next", "Next", show=False),
    Binding("N", "find_previous", "Previous", show=False),
    Binding("c", "clear_counters", "Clear"),
    Binding("r", "toggle_raw", "Raw"),
    Binding("v", "toggle_view", "View"),
    Binding("escape", "follow", "Follow", show=False),
    Binding("question_mark", "help", "Help", key_display="?"),
    Binding("f1", "help", "Help", show=False),
]
