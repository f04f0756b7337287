"""UAV state panel: GPS position, altitude, attitude and the last text message."""

from __future__ import annotations

from rich.text import Text
from textual.widgets import Static

from analyzer.protocol.types import TOPIC_UAV_ALTITUDE, TOPIC_UAV_ATTITUDE, TOPIC_UAV_GPS, Event
from analyzer.tui.formatting import short_age
from analyzer.tui.state import MonitorState


def _line(state: MonitorState, label: str, event: Event | None, body: str) -> Text:
    line = Text(f"{label:<9}", style="dim")
    if event is None:
        line.append("—")
        return line
    line.append(f"{body:<34}", style="bold")
    line.append(f"{short_age(state.age(event)):>7}", style="dim")
    if event.warnings:
        line.append("  ⚠ " + event.warnings[0], style="yellow")
    return line


def _hemisphere(value: float, positive: str, negative: str) -> str:
    return f"{abs(value):.7f}° {positive if value >= 0 else negative}"


def render_uav(state: MonitorState) -> Text:
    """The panel's text (also used by tests)."""
    lines: list[Text] = []
    gps = state.gps
    body = ""
    if gps is not None:
        lat = float(gps.fields.get("latitude_deg", 0.0))
        lon = float(gps.fields.get("longitude_deg", 0.0))
        body = f"{_hemisphere(lat, 'N', 'S')}  {_hemisphere(lon, 'E', 'W')}"
    lines.append(_line(state, "GPS", gps, body))
    alt = state.altitude
    body = f"{float(alt.fields.get('altitude_m', 0.0)):.2f} m" if alt is not None else ""
    lines.append(_line(state, "altitude", alt, body))
    att = state.uav_attitude
    body = ""
    if att is not None:
        f = att.fields
        body = (
            f"pitch {f.get('pitch_deg', 0.0):.2f} roll {f.get('roll_deg', 0.0):.2f} "
            f"yaw {f.get('yaw_deg', 0.0):.2f}°"
        )
    lines.append(_line(state, "attitude", att, body))
    message = state.text
    body = repr(str(message.fields.get("text", ""))) if message is not None else ""
    lines.append(_line(state, "text", message, body))
    rng = state.ranging
    body = ""
    if rng is not None:
        f = rng.fields
        body = (
            f"{f.get('distance_m', 0.0):.1f} m  to {f.get('latitude_deg', 0.0):.6f} "
            f"{f.get('longitude_deg', 0.0):.6f}"
            if f.get("success", True)
            else "no target (ranging failed)"
        )
    lines.append(_line(state, "laser", rng, body))
    rates = Text(f"{'rates':<9}", style="dim")
    for label, topic in (
        ("gps", TOPIC_UAV_GPS),
        ("alt", TOPIC_UAV_ALTITUDE),
        ("att", TOPIC_UAV_ATTITUDE),
    ):
        rates.append(f"{label} ", style="dim")
        rates.append(f"{state.topic_rates.get(topic, 0.0):5.1f}", style="bold")
        rates.append("  ")
    rates.append("Hz", style="dim")
    lines.append(rates)
    text = Text("\n").join(lines)
    text.no_wrap = True
    text.overflow = "ellipsis"
    return text


class UavPanel(Static):
    """Redrawn from the state at the app's refresh rate."""

    DEFAULT_CSS = """
    UavPanel { border: round $primary; padding: 0 1; height: 10;
        text-wrap: nowrap; text-overflow: ellipsis; }
    """

    def on_mount(self) -> None:
        self.border_title = "UAV"

    def show(self, state: MonitorState) -> None:
        self.update(render_uav(state))
