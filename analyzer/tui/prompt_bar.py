"""The one-line input that asks for a filter or a search text."""

from __future__ import annotations

from typing import ClassVar

from textual.binding import Binding, BindingType
from textual.message import Message
from textual.widgets import Input

PLACEHOLDERS = {
    "filter": "filter: /topic  0xID  name  -hide   (enter: apply, empty: show all, escape: cancel)",
    "search": "search the log   (enter: find, then n / N for the next match, escape: cancel)",
}


class PromptBar(Input):
    """Hidden until the app opens it for ``filter`` or ``search``."""

    DEFAULT_CSS = """
    PromptBar { dock: bottom; display: none; margin-bottom: 1; }
    PromptBar.-open { display: block; }
    """

    BINDINGS: ClassVar[list[BindingType]] = [Binding("escape", "cancel", "Cancel")]

    class Done(Message):
        """The user entered a value (``value`` is None when cancelled)."""

        def __init__(self, mode: str, value: str | None) -> None:
            super().__init__()
            self.mode = mode
            self.value = value

    def __init__(self, *, id: str | None = None) -> None:
        super().__init__(id=id)
        self.mode = ""

    def open(self, mode: str, value: str = "") -> None:
        """Show the prompt with ``value`` selected: typing replaces it, arrows keep it."""
        self.mode = mode
        self.placeholder = PLACEHOLDERS.get(mode, "")
        self.value = value
        self.add_class("-open")
        self.focus()
        self.select_all()
        # focusing a widget that was hidden completes after the next refresh
        self.call_after_refresh(self.select_all)

    def close(self) -> None:
        self.remove_class("-open")

    def on_input_submitted(self, event: Input.Submitted) -> None:
        event.stop()
        self.close()
        self.post_message(self.Done(self.mode, event.value))

    def action_cancel(self) -> None:
        self.close()
        self.post_message(self.Done(self.mode, None))
