"""The latest response finding (did the gimbal obey?) and the verdicts so far."""

from __future__ import annotations

from rich.text import Text

from analyzer.analysis.findings import VERDICTS
from analyzer.protocol.response_fields import verdict_word
from analyzer.tui.fit import fold, join_lines, pack
from analyzer.tui.fitted_panel import FittedPanel
from analyzer.tui.formatting import short_age
from analyzer.tui.state import MonitorState

VERDICT_STYLES = {
    "obeyed": "bold green",
    "partial": "bold yellow",
    "not_obeyed": "bold red",
    "unknown": "dim",
}
LABEL_WIDTH = 7


def response_lines(state: MonitorState, width: int) -> list[Text]:
    """The panel's lines at ``width`` cells: the latest finding, its sentence, the counts."""
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
    return lines


class ResponsePanel(FittedPanel):
    """Redrawn from the state at the app's refresh rate."""

    def on_mount(self) -> None:
        self.border_title = "Did it obey?"

    def lines(self, state: MonitorState, width: int) -> list[Text]:
        return response_lines(state, width)


def render_response(state: MonitorState, width: int = 76) -> Text:
    """The panel's text at ``width`` cells (also used by tests)."""
    return join_lines(response_lines(state, width))
