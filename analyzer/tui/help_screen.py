"""The help pop-up: every key and the filter syntax."""

from __future__ import annotations

from typing import ClassVar

from rich.table import Table
from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import VerticalScroll
from textual.screen import ModalScreen
from textual.widgets import Static

KEYS: tuple[tuple[str, str], ...] = (
    ("1 2 3 4 5", "small terminals: gimbal + UAV, log, CAN IDs, diagnostics, did it obey?"),
    ("q", "quit: stop the capture, finalise the recording"),
    ("p / space", "pause the display (capture and recording go on); again: resume and catch up"),
    ("f", "filter the log and the ID table (see below); empty: show all"),
    ("/", "search the log; n / N: next older / newer match"),
    ("c", "clear counters, per-ID counts and rates (totals since start stay)"),
    ("r", "raw view: show the raw bytes in the log"),
    ("v", "log view: commands + diagnostics + text, or every decoded topic"),
    ("up / down, pgup / pgdn, home", "move the cursor in the log (stops following)"),
    ("end / escape", "follow the newest entry again"),
    (
        "enter",
        "details of the selected event: its whole line (one cut short ends in …),"
        " every field and the raw bytes",
    ),
    ("tab", "switch between the log and the ID table"),
    ("enter on an ID row", "filter by that ID (enter again: show all)"),
    ("? / f1", "this help"),
)

FILTER_HELP = """\
Filter terms are separated by spaces. An entry is shown if any term matches it
and no term starting with '-' does:
  /uav            topics starting with /uav
  0xF01  #F01     a CAN ID (events decoded from that ID, and its table row)
  zoom            a command name, diagnostic kind or any text of the line
  -gimbal_control hide what matches
Example: "/gimbal -gimbal_control" shows commands and feedback except pan/tilt."""


def render_help() -> Table:
    table = Table.grid(padding=(0, 2))
    table.add_column(style="bold cyan", no_wrap=True)
    table.add_column()
    for key, what in KEYS:
        table.add_row(key, what)
    return table


class HelpScreen(ModalScreen[None]):
    """Any of escape / ? / q closes it."""

    DEFAULT_CSS = """
    HelpScreen { align: center middle; }
    HelpScreen > VerticalScroll {
        width: 100%; max-width: 100; height: auto; max-height: 100%;
        border: thick $accent; background: $surface; padding: 0 1;
    }
    """

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("escape", "close", "Close"),
        Binding("question_mark", "close", "Close", show=False),
        Binding("q", "close", "Close", show=False),
    ]

    def compose(self) -> ComposeResult:
        with VerticalScroll() as scroll:
            scroll.border_title = "gimbal-analyzer monitor: keys"
            yield Static(render_help())
            yield Static(Text("\n" + FILTER_HELP))

    def action_close(self) -> None:
        self.dismiss(None)
