"""Diagnostics: counters by kind (reset only on request), totals, frames and errors sparklines."""

from __future__ import annotations

from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Horizontal, Vertical
from textual.widgets import Sparkline, Static

from analyzer.protocol.types import DIAGNOSTIC_KINDS
from analyzer.timefmt import UTC, TimeZone
from analyzer.tui.fit import grid, join_lines, pack
from analyzer.tui.fitted_panel import FittedPanel
from analyzer.tui.formatting import format_time
from analyzer.tui.state import MonitorState


def counter_lines(state: MonitorState, width: int, zone: TimeZone = UTC) -> list[Text]:
    """Counters by kind since the last clear (as many columns as fit), totals since start
    (when last cleared: in ``zone``)."""
    c = state.counters
    cells: list[Text] = []
    kinds = (*DIAGNOSTIC_KINDS, "warnings", *sorted(set(c.kinds) - set(DIAGNOSTIC_KINDS)))
    name_width = max(len(k) for k in kinds)
    counts = [c.warnings if kind == "warnings" else c.kinds.get(kind, 0) for kind in kinds]
    count_width = max(len(f"{n:,}") for n in counts)
    for kind, n in zip(kinds, counts, strict=True):
        if kind not in DIAGNOSTIC_KINDS and kind != "warnings":
            style = "bold red"
        elif n == 0:
            style = "dim"
        else:
            style = "bold yellow" if kind in ("link", "warnings") else "bold red"
        cells.append(
            Text.assemble((f"{kind:>{name_width}} ", "dim"), (f"{n:<{count_width},}", style))
        )
    lines = grid(cells, width, gap=3)
    t = state.total
    totals = [Text("since start", "dim")]
    if t.frames or not t.chunks:  # a TCP or UART stream has no CAN frames to count
        totals.append(Text(f"{t.frames:,} frames"))
    if t.chunks:
        totals.append(Text(f"{t.chunks:,} chunks"))
    totals += [
        Text(f"{t.events:,} events"),
        Text(f"{t.errors:,} errors", "bold red" if t.errors else ""),
    ]
    if state.cleared_at is not None:
        when = format_time(state.cleared_at, zone).strip()
        totals.append(Text(f"(cleared {state.clear_count}x, last {when})", "dim"))
    lines += pack(totals, width, indent=2)
    if state.dropped_batches:
        lines.append(Text(f"display skipped {state.dropped_batches} batches", "bold yellow"))
    return lines


def render_counters(state: MonitorState, width: int = 76) -> Text:
    """The counters' text at ``width`` cells (also used by tests)."""
    return join_lines(counter_lines(state, width))


class CountersView(FittedPanel):
    """The counters part of the panel (no border of its own)."""

    DEFAULT_CSS = """
    CountersView { border: none; padding: 0 1 0 0; }
    """

    def __init__(self, *, id: str | None = None, zone: TimeZone = UTC) -> None:
        super().__init__(id=id)
        self.zone = zone

    def lines(self, state: MonitorState, width: int) -> list[Text]:
        return counter_lines(state, width, self.zone)


class DiagnosticsPanel(Horizontal):
    """Counters on the left, two sparklines on the right."""

    DEFAULT_CSS = """
    DiagnosticsPanel { border: round $primary; height: auto; }
    DiagnosticsPanel #diag-counters { width: 1fr; }
    DiagnosticsPanel #diag-graphs { width: 40; height: 6; padding: 0 1; }
    DiagnosticsPanel Sparkline { height: 2; margin: 0 0 0 0; }
    DiagnosticsPanel #errors-spark > .sparkline--max-color { color: $error; }
    DiagnosticsPanel #errors-spark > .sparkline--min-color { color: $error 30%; }
    """

    def __init__(self, *, id: str | None = None, zone: TimeZone = UTC) -> None:
        super().__init__(id=id)
        self._counters = CountersView(id="diag-counters", zone=zone)
        self._frames_label = Static(id="frames-label")
        self._frames = Sparkline([0.0], id="frames-spark")
        self._errors_label = Static(id="errors-label")
        self._errors = Sparkline([0.0], id="errors-spark")

    def compose(self) -> ComposeResult:
        yield self._counters
        with Vertical(id="diag-graphs"):
            yield self._frames_label
            yield self._frames
            yield self._errors_label
            yield self._errors

    def on_mount(self) -> None:
        self.border_title = "Diagnostics"

    def show(self, state: MonitorState) -> None:
        self._counters.show(state)
        frames = list(state.frames_history)
        errors = list(state.errors_history)
        n = len(frames)
        self._frames_label.update(
            Text.assemble(
                (f"{'chunks' if state.items_counted == 'chunks' else 'frames'}/s ", "dim"),
                f"{state.frames_per_s:,.0f}",
                (f"  max {max(frames):,.0f}", "dim"),
            )
        )
        self._frames.data = frames
        self._errors_label.update(
            Text.assemble(
                ("errors/s ", "dim"),
                (f"{state.errors_per_s:,.1f}", "bold red" if state.errors_per_s else ""),
                (f"  last {n} s", "dim"),
            )
        )
        self._errors.data = errors
