"""Where the monitor's panels go: all on one screen, or one page at a time on a small terminal."""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from textual.app import ComposeResult
from textual.containers import Horizontal
from textual.widgets import Footer
from textual.widgets._footer import FooterKey

from analyzer.timefmt import UTC, TimeZone
from analyzer.tui.command_log import CommandLog
from analyzer.tui.diagnostics_panel import DiagnosticsPanel
from analyzer.tui.gimbal_panel import GimbalPanel
from analyzer.tui.id_table import IdTable
from analyzer.tui.prompt_bar import PromptBar
from analyzer.tui.response_panel import ResponsePanel
from analyzer.tui.status_bar import StatusBar
from analyzer.tui.uav_panel import UavPanel

# The all-in-one screen needs this much room; smaller terminals show one page at a time.
WIDE_WIDTH = 120
WIDE_HEIGHT = 36
SIDE_BY_SIDE_WIDTH = 110  # gimbal and UAV panels next to each other on the first page
ROOMY_HEIGHT = 30  # the first page also shows the log

# number key -> (page, name in the footer)
PAGES: dict[str, tuple[str, str]] = {
    "1": ("state", "Gimbal"),
    "2": ("log", "Log"),
    "3": ("ids", "IDs"),
    "4": ("diagnostics", "Diag"),
    "5": ("response", "Obey?"),
}
# keys left out of the footer when it has to make room for the page keys (they still work)
PAGED_FOOTER_HIDES = frozenset(
    {"toggle_pause", "clear_counters", "toggle_raw", "toggle_view", "select", "select_cursor"}
)

# Textual sets these classes on the screen from its size; MONITOR_CSS uses them
HORIZONTAL_BREAKPOINTS: list[tuple[int, str]] = [
    (0, "-narrow"),
    (SIDE_BY_SIDE_WIDTH, "-medium"),
    (WIDE_WIDTH, "-wide"),
]
VERTICAL_BREAKPOINTS: list[tuple[int, str]] = [
    (0, "-short"),
    (ROOMY_HEIGHT, "-roomy"),
    (WIDE_HEIGHT, "-tall"),
]

MONITOR_CSS = """
#top { height: auto; }
#top GimbalPanel { width: 1fr; }
#top UavPanel { width: 1fr; }
#middle { height: 1fr; }
#middle CommandLog { width: 1fr; }
#middle IdTable { width: 62; }

/* one page at a time: 1 gimbal + UAV (+ log when there is room), 2 log, 3 IDs, 4 diagnostics,
   5 did it obey? (the latest findings) */
Screen.-paged #diagnostics { display: none; layout: vertical; height: 1fr; }
Screen.-paged #diagnostics #diag-graphs { width: 1fr; }
Screen.-paged #ids { display: none; width: 1fr; }
Screen.-paged.-narrow #top { layout: vertical; }
Screen.-paged.-short.-page-state #middle { display: none; }
Screen.-paged.-page-log #top { display: none; }
Screen.-paged #response { display: none; }
Screen.-paged.-page-state.-roomy #response { display: block; }
Screen.-paged.-page-ids #top { display: none; }
Screen.-paged.-page-ids #log { display: none; }
Screen.-paged.-page-ids #ids { display: block; }
Screen.-paged.-page-diagnostics #top { display: none; }
Screen.-paged.-page-diagnostics #middle { display: none; }
Screen.-paged.-page-diagnostics #diagnostics { display: block; }
Screen.-paged.-page-response #top { display: none; }
Screen.-paged.-page-response #middle { display: none; }
Screen.-paged.-page-response #response { display: block; height: 1fr; }
"""


def is_paged(width: int, height: int) -> bool:
    """Whether a terminal of this size shows one page at a time."""
    return width < WIDE_WIDTH or height < WIDE_HEIGHT


@runtime_checkable
class PagedApp(Protocol):
    """An app that may show one page at a time (the monitor)."""

    @property
    def paged(self) -> bool: ...


class MonitorFooter(Footer):
    """The footer, leaving out the less used keys when the screen is paged (see ? for all)."""

    def compose(self) -> ComposeResult:
        app = self.app
        hidden = PAGED_FOOTER_HIDES if isinstance(app, PagedApp) and app.paged else frozenset()
        for widget in super().compose():
            if isinstance(widget, FooterKey) and widget.action in hidden:
                continue
            yield widget


def compose_monitor(zone: TimeZone = UTC) -> ComposeResult:
    """Every panel of the monitor, their times in ``zone``; the CSS shows all of them or
    those of the current page."""
    yield StatusBar(id="status")
    with Horizontal(id="top"):
        yield GimbalPanel(id="gimbal")
        yield UavPanel(id="uav")
    yield ResponsePanel(id="response", zone=zone)
    with Horizontal(id="middle"):
        yield CommandLog(id="log", zone=zone)
        yield IdTable(id="ids")
    yield DiagnosticsPanel(id="diagnostics", zone=zone)
    yield PromptBar(id="prompt")
    yield MonitorFooter()
