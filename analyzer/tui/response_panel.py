"""The latest response finding (did the gimbal obey?) and the verdicts so far."""

from __future__ import annotations

from rich.text import Text

from analyzer.analysis.findings import VERDICTS
from analyzer.protocol.response_fields import verdict_word
from analyzer.protocol.types import Event
from analyzer.timefmt import UTC, TimeZone
from analyzer.tui.fit import fold, join_lines, pack
from analyzer.tui.fitted_panel import FittedPanel
from analyzer.tui.formatting import format_time, short_age
from analyzer.tui.state import MonitorState

VERDICT_STYLES = {
    "obeyed": "bold green",
    "partial": "bold yellow",
    "not_obeyed": "bold red",
    "unknown": "dim",
    "healthy": "bold green",
    "degraded": "bold yellow",
    "lost": "bold red",
}
LABEL_WIDTH = 7
# The figures of a finding shown under its sentence: (field, how it is written).
FIGURES = (
    ("pan_ratio", "pan x{:.2f}"),
    ("tilt_ratio", "tilt x{:.2f}"),
    ("lag_s", "lag {:.2f} s"),
    ("command_count", "{:,} commands"),
    ("interval_mean_s", "every {:.2f} s"),
    ("updates_hz", "{:.1f} updates/s"),
    ("response_s", "in {:.2f} s"),
)


def figure_cells(fields: dict[str, object]) -> list[Text]:
    """A finding's ratios, lag and cadence, each a short cell (none for a plain finding)."""
    cells = []
    for key, form in FIGURES:
        value = fields.get(key)
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            if key == "command_count" and value < 2:
                continue
            cells.append(Text(form.format(value), style="cyan"))
    return cells


def response_lines(
    state: MonitorState, width: int, earlier: bool = False, zone: TimeZone = UTC
) -> list[Text]:
    """The panel's lines at ``width`` cells: the latest finding, its sentence, the counts;
    with ``earlier`` the findings before it, newest first, each in full (timed in ``zone``)."""
    finding = state.finding
    head = Text(f"{'last':<{LABEL_WIDTH}}", style="dim")
    if finding is None:
        return [head + Text("—  commands are judged from the attitude feedback that follows")]
    f = finding.fields
    verdict = str(f.get("verdict", "unknown"))
    cells = [
        head
        + Text(verdict_word(f).upper(), style=VERDICT_STYLES.get(verdict, "bold"))
        + Text(f"  {f.get('command', '?')} {f.get('check', '')}", style="bold"),
        Text(short_age(state.age(finding)), style="dim"),
    ]
    lines = pack(cells, width, indent=LABEL_WIDTH)
    figures = figure_cells(f)
    if figures:
        lines += pack([Text(" " * (LABEL_WIDTH - 2)), *figures], width, indent=LABEL_WIDTH)
    detail = Text(str(f.get("detail", "")))
    lines += [Text(" " * LABEL_WIDTH) + piece for piece in fold(detail, width - LABEL_WIDTH)]
    counts = [Text(f"{'so far':<{LABEL_WIDTH - 2}}", style="dim")]
    for name in VERDICTS:
        counts.append(
            Text.assemble(
                (str(state.verdicts.get(name, 0)), VERDICT_STYLES[name]),
                (f" {name.replace('_', ' ')}", "dim"),
            )
        )
    lines += pack(counts, width, indent=LABEL_WIDTH)
    if earlier:
        before = list(state.findings)[-2::-1]
        if before:
            lines.append(Text("earlier", style="dim"))
        for event in before:
            lines += earlier_lines(event, width, zone)
    return lines


def earlier_lines(event: Event, width: int, zone: TimeZone = UTC) -> list[Text]:
    """One earlier finding: its time, verdict and command, then its sentence, in full."""
    f = event.fields
    verdict = str(f.get("verdict", "unknown"))
    head = Text.assemble(
        (format_time(event.time, zone).strip() + "  ", "dim"),
        (verdict_word(f).upper(), VERDICT_STYLES.get(verdict, "bold")),
        (f"  {f.get('command', '?')} {f.get('check', '')}", "bold"),
    )
    lines = fold(head, width)
    detail = Text(str(f.get("detail", "")))
    return lines + [Text("  ") + piece for piece in fold(detail, width - 2)]


class ResponsePanel(FittedPanel):
    """Redrawn from the state at the app's refresh rate; ``earlier`` (its own page) lists
    the findings before the latest too."""

    earlier = False

    def __init__(self, *, id: str | None = None, zone: TimeZone = UTC) -> None:
        super().__init__(id=id)
        self.zone = zone

    def on_mount(self) -> None:
        self.border_title = "Did it obey?"

    def lines(self, state: MonitorState, width: int) -> list[Text]:
        return response_lines(state, width, self.earlier, self.zone)


def render_response(state: MonitorState, width: int = 76) -> Text:
    """The panel's text at ``width`` cells (also used by tests)."""
    return join_lines(response_lines(state, width))
