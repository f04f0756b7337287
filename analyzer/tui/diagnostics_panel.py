"""Diagnostics: counters by kind (reset only on request), totals, frames and errors sparklines."""

from __future__ import annotations

from rich.text import Text
from textual.app import ComposeResult
from textual.containers import Horizontal, Vertical
from textual.widgets import Sparkline, Static

from analyzer.protocol.types import DIAGNOSTIC_KINDS
from analyzer.tui.formatting import format_time
from analyzer.tui.state import MonitorState


def render_counters(state: MonitorState) -> Text:
    """Counters by kind since the last clear, totals since start (never reset)."""
    c = state.counters
    text = Text()
    for i, kind in enumerate((*DIAGNOSTIC_KINDS, "warnings")):
        n = c.warnings if kind == "warnings" else c.kinds.get(kind, 0)
        if i and i % 3 == 0:
            text.append("\n")
        style = "dim" if n == 0 else ("bold yellow" if kind in ("link", "warnings") else "bold red")
        text.append(f"{kind:>17} ", "dim")
        text.append(f"{n:<7,}", style)
    others = sorted(set(c.kinds) - set(DIAGNOSTIC_KINDS))
    for kind in others:
        text.append(f"\n{kind:>17} ", "dim")
        text.append(f"{c.kinds[kind]:<7,}", "bold red")
    t = state.total
    text.append("\n")
    text.append("since start ", "dim")
    text.append(f"{t.frames:,} frames  {t.chunks:,} chunks  {t.events:,} events  ")
    text.append(f"{t.errors:,} errors", "bold red" if t.errors else "")
    if state.cleared_at is not None:
        when = format_time(state.cleared_at)
        text.append(f"  (cleared {state.clear_count}x, last {when})", "dim")
    if state.dropped_batches:
        text.append(f"\ndisplay skipped {state.dropped_batches} batches", "bold yellow")
    return text


class DiagnosticsPanel(Horizontal):
    """Counters on the left, two sparklines on the right."""

    DEFAULT_CSS = """
    DiagnosticsPanel { border: round $primary; height: 8; }
    DiagnosticsPanel #diag-counters { width: 1fr; }
    DiagnosticsPanel #diag-graphs { width: 40; padding: 0 1; }
    DiagnosticsPanel Sparkline { height: 2; margin: 0 0 0 0; }
    DiagnosticsPanel #errors-spark > .sparkline--max-color { color: $error; }
    DiagnosticsPanel #errors-spark > .sparkline--min-color { color: $error 30%; }
    """

    def __init__(self, *, id: str | None = None) -> None:
        super().__init__(id=id)
        self._counters = Static(id="diag-counters")
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
        self._counters.update(render_counters(state))
        frames = list(state.frames_history)
        errors = list(state.errors_history)
        n = len(frames)
        self._frames_label.update(
            Text.assemble(
                ("frames/s ", "dim"),
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
