"""UAV state panel: GPS position, altitude, attitude and the last text message."""

from __future__ import annotations

from rich.text import Text

from analyzer.protocol.types import TOPIC_UAV_ALTITUDE, TOPIC_UAV_ATTITUDE, TOPIC_UAV_GPS, Event
from analyzer.tui.fit import join_lines, pack
from analyzer.tui.fitted_panel import FittedPanel
from analyzer.tui.formatting import short_age
from analyzer.tui.state import MonitorState

LABEL_WIDTH = 9


def _hemisphere(value: float, positive: str, negative: str) -> str:
    return f"{abs(value):.7f}° {positive if value >= 0 else negative}"


def _rows(state: MonitorState) -> list[tuple[str, Event | None, str]]:
    """(label, event, value in words) per line of the panel."""
    gps = state.gps
    position = ""
    if gps is not None:
        lat = float(gps.fields.get("latitude_deg", 0.0))
        lon = float(gps.fields.get("longitude_deg", 0.0))
        position = f"{_hemisphere(lat, 'N', 'S')}  {_hemisphere(lon, 'E', 'W')}"
    alt = state.altitude
    altitude = f"{float(alt.fields.get('altitude_m', 0.0)):.2f} m" if alt is not None else ""
    att = state.uav_attitude
    attitude = ""
    if att is not None:
        f = att.fields
        attitude = (
            f"pitch {f.get('pitch_deg', 0.0):.2f} roll {f.get('roll_deg', 0.0):.2f} "
            f"yaw {f.get('yaw_deg', 0.0):.2f}°"
        )
    message = state.text
    text = repr(str(message.fields.get("text", ""))) if message is not None else ""
    rng = state.ranging
    laser = ""
    if rng is not None:
        f = rng.fields
        laser = (
            f"{f.get('distance_m', 0.0):.1f} m  to {f.get('latitude_deg', 0.0):.6f} "
            f"{f.get('longitude_deg', 0.0):.6f}"
            if f.get("success", True)
            else "no target (ranging failed)"
        )
    return [
        ("GPS", gps, position),
        ("altitude", alt, altitude),
        ("attitude", att, attitude),
        ("text", message, text),
        ("laser", rng, laser),
    ]


def uav_lines(state: MonitorState, width: int) -> list[Text]:
    """The panel's lines at ``width`` cells: ages in a column when they fit, values never cut."""
    rows = _rows(state)
    # ages line up in a column after the values that leave room for it
    room = width - LABEL_WIDTH - 2 - 6
    body_width = max((len(b) for _, e, b in rows if e is not None and len(b) <= room), default=0)
    lines: list[Text] = []
    for label, event, body in rows:
        head = Text(f"{label:<{LABEL_WIDTH}}", style="dim")
        if event is None:
            lines.append(head + Text("—"))
            continue
        age = Text(short_age(state.age(event)), style="dim")
        value = Text(body, style="bold")
        if len(body) <= body_width:
            value.pad_right(body_width - len(body))
            age.pad_left(6 - age.cell_len)
        cells = [head + value, age]
        if event.warnings:
            cells.append(Text("⚠ " + event.warnings[0], style="yellow"))
        lines += pack(cells, width, indent=LABEL_WIDTH)
    rates = [Text(f"{'rates':<{LABEL_WIDTH - 2}}", style="dim")]
    for label, topic in (
        ("gps", TOPIC_UAV_GPS),
        ("alt", TOPIC_UAV_ALTITUDE),
        ("att", TOPIC_UAV_ATTITUDE),
    ):
        rates.append(
            Text.assemble(
                (f"{label} ", "dim"), (f"{state.topic_rates.get(topic, 0.0):.1f}", "bold")
            )
        )
    rates.append(Text("Hz", style="dim"))
    lines += pack(rates, width, indent=LABEL_WIDTH)
    return lines


def render_uav(state: MonitorState, width: int = 76) -> Text:
    """The panel's text at ``width`` cells (also used by tests)."""
    return join_lines(uav_lines(state, width))


class UavPanel(FittedPanel):
    """Redrawn from the state at the app's refresh rate."""

    def on_mount(self) -> None:
        self.border_title = "UAV"

    def lines(self, state: MonitorState, width: int) -> list[Text]:
        return uav_lines(state, width)
