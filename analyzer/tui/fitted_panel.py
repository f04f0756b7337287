"""A panel whose text is laid out for its current width and whose height follows the text."""

from __future__ import annotations

from rich.text import Text
from textual.geometry import Size
from textual.widget import Widget

from analyzer.tui.fit import join_lines
from analyzer.tui.state import MonitorState


class FittedPanel(Widget):
    """Subclasses say what lines they show at a width; the panel grows rather than cut them."""

    DEFAULT_CSS = """
    FittedPanel { border: round $primary; padding: 0 1; height: auto; }
    """

    def __init__(self, *, id: str | None = None) -> None:
        super().__init__(id=id)
        self.state: MonitorState | None = None
        self._lines = 0
        self.min_rows = 0  # pad to this many lines (to match a panel beside it)

    def lines(self, state: MonitorState, width: int) -> list[Text]:
        raise NotImplementedError

    def _lines_at(self, width: int) -> list[Text]:
        lines = [Text()] if self.state is None else self.lines(self.state, width)
        if len(lines) < self.min_rows:
            lines += [Text()] * (self.min_rows - len(lines))
        return lines

    def rows_at(self, width: int) -> int:
        """How many lines the content takes at ``width`` (without padding)."""
        if self.state is None or width <= 0:
            return 1
        return len(self.lines(self.state, width))

    def text(self, width: int | None = None) -> str:
        """The panel's plain text at ``width`` (default: its current width), for tests."""
        return join_lines(self._lines_at(width or self.size.width)).plain

    def show(self, state: MonitorState) -> None:
        self.state = state
        n = len(self._lines_at(self.size.width)) if self.size.width else self._lines
        self.refresh(layout=n != self._lines)
        self._lines = n

    def render(self) -> Text:
        lines = self._lines_at(self.size.width)
        self._lines = len(lines)
        return join_lines(lines)

    def get_content_height(self, container: Size, viewport: Size, width: int) -> int:
        return len(self._lines_at(width)) if width else 1
