"""Plain-text wording of events, times, ages and value bars for the TUI (no UI code)."""

from __future__ import annotations

from collections.abc import Mapping

from analyzer import render
from analyzer.protocol.types import (
    TO_IDU,
    Event,
)
from analyzer.timefmt import UTC, TimeZone


def format_time(t: float, zone: TimeZone = UTC) -> str:
    """Wall-clock HH:MM:SS.mmm (UTC with Z, or local time with its offset: ``zone``, the
    one time rule of ``analyzer.timefmt``) for Unix times, seconds for relative times."""
    return render.format_time(t, zone).rjust(zone.clock_width)


def _age(age: float, units: tuple[str, str, str]) -> str:
    """Seconds below two minutes, minutes below two hours, then hours."""
    seconds, minutes, hours = units
    age = max(age, 0.0)
    if age < 10:
        return f"{age:.2f}{seconds}"
    if age < 120:
        return f"{age:.0f}{seconds}"
    if age < 7200:
        return f"{age / 60:.0f}{minutes}"
    return f"{age / 3600:.0f}{hours}"


def format_age(age: float | None) -> str:
    """How long ago, e.g. '0.25 s', '12 s', '3 min'; 'never' for None."""
    return "never" if age is None else _age(age, (" s", " min", " h"))


def short_age(age: float | None) -> str:
    """Compact age for tight columns: '0.25s', '12s', '3m', '2h'; '—' for None."""
    return "—" if age is None else _age(age, ("s", "m", "h"))


def format_size(size: int | None) -> str:
    """A file size in B / kB / MB / GB."""
    if size is None:
        return "?"
    value = float(size)
    for unit in ("B", "kB", "MB", "GB"):
        if value < 1000 or unit == "GB":
            return f"{value:.0f} {unit}" if unit == "B" else f"{value:.1f} {unit}"
        value /= 1000
    return f"{size} B"  # pragma: no cover


def describe_params(event: Event) -> str:
    """An event's values in plain words, single-spaced for narrow panels."""
    return " ".join(render.describe(event).split())


def event_text(event: Event, zone: TimeZone = UTC) -> str:
    """One line of plain words for an event (without the time column; the moments among
    its values in ``zone``)."""
    try:
        text = " ".join(render.describe_event(event, zone).split())
    except Exception:  # a wording bug must not take the monitor down
        text = f"{event.topic} {event.fields}"
    direction = event.fields.get("direction")
    if direction:
        text = ("→ idu " if direction == TO_IDU else "← idu ") + text
    return text


def folded_text(text: str, name: str, count: int, span: float) -> str:
    """The words of ``count`` commands folded into one line (``text``: the last one's):
    'gimbal_control x20 in 1.0 s, last pan 12.00 deg/s tilt 0.00 deg/s'."""
    at = text.find(name) if name else -1
    if at < 0:
        return f"x{count} in {span:.1f} s, last {text}"
    end = at + len(name)
    rest = text[end:].strip()
    return f"{text[:end]} x{count} in {span:.1f} s" + (f", last {rest}" if rest else "")


def event_raw(event: Event) -> str:
    """The raw bytes of an event as hex, or '' when the event carries none."""
    raw = event.fields.get("raw")
    if raw:
        return str(raw)
    data = event.fields.get("data")
    return str(data) if data else ""


def value_bar(value: float | None, low: float, high: float, width: int = 24) -> str:
    """A one-line gauge: '[-----|--o-------]' with '|' at zero and 'o' at the value."""
    inner = max(width - 2, 3)
    cells = ["-"] * inner

    def position(v: float) -> int:
        frac = (min(max(v, low), high) - low) / (high - low)
        return min(round(frac * (inner - 1)), inner - 1)

    if low < 0 < high:
        cells[position(0.0)] = "|"
    if value is not None:
        cells[position(value)] = "o"
    return "[" + "".join(cells) + "]"


_COMPASS = ("N", "NE", "E", "SE", "S", "SW", "W", "NW")


def compass(yaw_deg: float) -> str:
    """Compass point of a heading: 'N', 'NE', ..."""
    return _COMPASS[int(((yaw_deg % 360) + 22.5) // 45) % 8]


def labelled(fields: Mapping[str, object], name: str) -> tuple[str, int | None]:
    """(label, raw code) of a labelled field: ``X`` holds the label, ``X_code`` the raw integer."""
    label = fields.get(name)
    code = fields.get(f"{name}_code")
    raw = code if isinstance(code, int) and not isinstance(code, bool) else None
    if isinstance(label, str) and label:
        return label, raw
    return ("?" if raw is None else f"unknown_0x{raw:02x}"), raw
