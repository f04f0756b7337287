"""Status line: source, connection state, recording and its size, frames/s, bus load."""

from __future__ import annotations

from dataclasses import dataclass

from rich.text import Text

from analyzer.bus_figures import BusFigures, status_words
from analyzer.protocol.bus_state import LEVELS
from analyzer.timefmt import UTC, TimeZone
from analyzer.tui.fit import join_lines, pack
from analyzer.tui.fitted_panel import FittedPanel
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
    live: str = ""  # the live Foxglove server: clients, slow-client drops ('' without one)
    live_alert: bool = False  # a client too slow for the stream lost messages
    zone: TimeZone = UTC  # the times shown (when the link was lost, the worst bus state)


def link_text(state: MonitorState, zone: TimeZone = UTC) -> tuple[str, str]:
    """(words, style) for the connection state, from the last link diagnostic."""
    link = state.link
    words = link.describe(state.now, zone)
    if state.source_ended:
        return ("ended: " + words if link.failing and words else "source ended"), "bold yellow"
    if link.seen:
        if link.good:
            return words, "bold green"
        if link.failing:
            return words, "bold white on red"
        return words, "bold yellow"
    if state.total.frames or state.total.chunks:
        return "receiving", "bold green"
    return "waiting for data", "yellow"


# Style of each CAN controller state, from error-active to bus-off.
BUS_STYLES = ("bold green", "bold yellow", "bold red", "bold white on red")


def bus_cell(bus: BusFigures, zone: TimeZone = UTC) -> Text | None:
    """``CAN bus-off │ worst bus-off 10:00:08.000Z │ 46 errors: bus-error 40, ...``."""
    words = status_words(bus, zone)
    if words is None:
        return None
    cell = Text(f" {words.now} ", BUS_STYLES[LEVELS.get(words.state, 0)])
    if words.worst:
        cell.append(f" {words.worst}", BUS_STYLES[LEVELS.get(words.worst_state, 0)])
    cell.append(f"  {words.errors}", "dim")
    return cell


def status_cells(state: MonitorState, info: StatusInfo) -> list[Text]:
    """The status line's parts: source and link, recording, rates, view, filter, pause."""
    source = Text.assemble(
        (" ● ", "bold green" if not state.source_ended else "yellow"), (info.source or "?", "bold")
    )
    words, style = link_text(state, info.zone)
    cells = [source, Text(f" {words} ", style)]
    if info.recording:
        rec = Text("REC ", "bold red")
        rec.append(f"{info.recording} {format_size(info.recording_size)}")
        cells.append(rec)
    else:
        cells.append(Text("not recording", "dim"))
    rates = Text(f"{state.frames_per_s:,.0f}", "bold")
    if state.total.chunks and not state.total.frames:
        rates.append(" chunks/s", "dim")  # a TCP / UART stream: no CAN bus to load
    else:
        rates.append(" frames/s  bus ", "dim")
        load = state.bus_load * 100
        rates.append(f"{load:.1f}%", "bold red" if load >= 80 else "bold")
    cells.append(rates)
    bus = bus_cell(state.bus, info.zone)
    if bus is not None:
        cells.append(bus)
    if info.dropped:
        cells.append(Text(f" {info.dropped:,} DROPPED ", "bold white on red"))
    if info.live:
        cells.append(
            Text(
                f" {info.live} " if info.live_alert else info.live,
                "bold white on red" if info.live_alert else "bold cyan",
            )
        )
    if info.view != "commands" or info.raw:  # the default view goes without saying
        view = Text(f"view {info.view}", "dim")
        if info.raw:
            view.append(" raw", "dim")
        cells.append(view)
    if info.filter_text:
        cells.append(Text(f"filter {info.filter_text}", "bold magenta"))
    if info.paused:
        cells.append(Text(f" PAUSED +{info.paused_new} ", "bold black on yellow"))
    return cells


def status_lines(state: MonitorState, info: StatusInfo, width: int) -> list[Text]:
    """The status at ``width`` cells: one line when it fits, more when the terminal is narrow."""
    return pack(status_cells(state, info), width, joiner=Text(" │ ", "dim"), indent=3)


def render_status(state: MonitorState, info: StatusInfo, width: int = 200) -> Text:
    return join_lines(status_lines(state, info, width))


class StatusBar(FittedPanel):
    """The line(s) at the top of the screen."""

    DEFAULT_CSS = """
    StatusBar { border: none; padding: 0; background: $panel; }
    """

    def __init__(self, *, id: str | None = None) -> None:
        super().__init__(id=id)
        self.info = StatusInfo()

    def show_status(self, state: MonitorState, info: StatusInfo) -> None:
        self.info = info
        self.show(state)

    def lines(self, state: MonitorState, width: int) -> list[Text]:
        return status_lines(state, self.info, width)
