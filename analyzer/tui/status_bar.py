"""Status line: source, connection state, recording and its size, frames/s, bus load."""

from __future__ import annotations

from dataclasses import dataclass

from rich.text import Text
from textual.widgets import Static

from analyzer.tui.formatting import format_size
from analyzer.tui.state import MonitorState


@dataclass
class StatusInfo:
    """What the status line needs besides the state."""

    source: str = ""
    recording: str | None = None
    recording_size: int | None = None
    paused: bool = False
    paused_new: int = 0
    filter_text: str = ""
    view: str = "commands"
    raw: bool = False
    dropped: int = 0  # frames / chunks the source dropped because the capture fell behind


_GOOD_STATES = frozenset({"open", "connected", "gs_connected"})
_WAIT_STATES = frozenset({"listening", "reconnecting", "connecting"})
_BAD_WORDS = ("down", "lost", "disconnect", "error", "fail", "refused", "closed")


def link_text(state: MonitorState) -> tuple[str, str]:
    """(words, style) for the connection state, from the last link diagnostic."""
    link = state.link_state
    detail = state.link_detail
    bad = any(w in (link or detail).lower() for w in _BAD_WORDS)
    if state.source_ended:
        return ("ended: " + detail if bad and detail else "source ended"), "bold yellow"
    if link or detail:
        words = link or detail
        if link in _GOOD_STATES:
            return words, "bold green"
        if link in _WAIT_STATES or not bad:
            return (f"{link}: {detail}" if link and detail else words), "bold yellow"
        return (f"{link}: {detail}" if link and detail else words), "bold white on red"
    if state.total.frames or state.total.chunks:
        return "receiving", "bold green"
    return "waiting for data", "yellow"


def render_status(state: MonitorState, info: StatusInfo) -> Text:
    text = Text(no_wrap=True, overflow="ellipsis")
    text.append(" ● ", "bold green" if not state.source_ended else "yellow")
    text.append(info.source or "?", "bold")
    words, style = link_text(state)
    text.append("  ")
    text.append(f" {words} ", style)
    text.append("  │ ", "dim")
    if info.recording:
        text.append("REC ", "bold red")
        text.append(f"{info.recording} {format_size(info.recording_size)}")
    else:
        text.append("not recording", "dim")
    text.append(" │ ", "dim")
    text.append(f"{state.frames_per_s:,.0f}", "bold")
    if state.total.chunks and not state.total.frames:
        text.append(" chunks/s", "dim")  # a TCP / UART stream: no CAN bus to load
    else:
        text.append(" frames/s  bus ", "dim")
        load = state.bus_load * 100
        text.append(f"{load:.1f}%", "bold red" if load >= 80 else "bold")
    if info.dropped:
        text.append(" │ ", "dim")
        text.append(f" {info.dropped:,} DROPPED ", "bold white on red")
    text.append(" │ ", "dim")
    text.append(f"view {info.view}", "dim")
    if info.raw:
        text.append(" raw", "dim")
    if info.filter_text:
        text.append(" │ ", "dim")
        text.append(f"filter {info.filter_text}", "bold magenta")
    if info.paused:
        text.append(" │ ", "dim")
        text.append(f" PAUSED +{info.paused_new} ", "bold black on yellow")
    return text


class StatusBar(Static):
    """One line at the top of the screen."""

    DEFAULT_CSS = """
    StatusBar { height: 1; background: $panel; }
    """

    def show(self, state: MonitorState, info: StatusInfo) -> None:
        self.update(render_status(state, info))
