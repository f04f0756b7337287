"""Plain-text wording of events, times, ages and value bars for the TUI (no UI code)."""

from __future__ import annotations

import time as _time
from collections.abc import Callable, Mapping
from typing import Any

from analyzer.protocol.types import (
    TO_IDU,
    TOPIC_CAN_OTHER,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_GIMBAL_RANGING,
    TOPIC_UAV_ALTITUDE,
    TOPIC_UAV_ATTITUDE,
    TOPIC_UAV_GPS,
    TOPIC_UAV_TEXT,
    Event,
)

# Fields that say where an event came from or repeat its identity; not parameters.
_META_FIELDS = frozenset(
    {"s_id", "cmd", "name", "component", "raw", "transport", "direction", "crc_set", "byte_count"}
)

# Unit suffix of a field name -> (unit text, decimals).
_UNITS: tuple[tuple[str, str, int], ...] = (
    ("_speed_dps", "deg/s", 2),
    ("_dps", "deg/s", 2),
    ("_deg", "deg", 2),
    ("_pct", "%", 2),
    ("_m", "m", 2),
    ("_s", "s", 0),
)

EPOCH_THRESHOLD = 1e8  # times above this are Unix times, below: seconds since the log start


def format_time(t: float) -> str:
    """Wall-clock HH:MM:SS.mmm for Unix times, seconds with milliseconds for relative times."""
    if t >= EPOCH_THRESHOLD:
        whole = int(t)
        millis = int((t - whole) * 1000)
        return _time.strftime("%H:%M:%S", _time.localtime(whole)) + f".{millis:03d}"
    return f"{t:12.3f}"


def format_age(age: float | None) -> str:
    """How long ago, e.g. '0.25 s', '12 s', '3 min'; 'never' for None."""
    if age is None:
        return "never"
    age = max(age, 0.0)
    if age < 10:
        return f"{age:.2f} s"
    if age < 120:
        return f"{age:.0f} s"
    if age < 7200:
        return f"{age / 60:.0f} min"
    return f"{age / 3600:.0f} h"


def short_age(age: float | None) -> str:
    """Compact age for tight columns: '0.25s', '12s', '3m', '2h'; '—' for None."""
    if age is None:
        return "—"
    age = max(age, 0.0)
    if age < 10:
        return f"{age:.2f}s"
    if age < 120:
        return f"{age:.0f}s"
    if age < 7200:
        return f"{age / 60:.0f}m"
    return f"{age / 3600:.0f}h"


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


def format_value(key: str, value: Any) -> tuple[str, str]:
    """A field as (label, value-with-unit): ('pan', '-5.00 deg/s')."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return key, str(value)
    if key.startswith(("latitude", "longitude")):
        return key.removesuffix("_deg"), f"{value:.7f}"
    for suffix, unit, decimals in _UNITS:
        if key.endswith(suffix):
            label = key[: -len(suffix)] or key
            return label, f"{value:.{decimals}f} {unit}"
    if isinstance(value, float):
        return key, f"{value:.2f}"
    return key, str(value)


# Enum-like fields whose label alone says enough ("zoom_in", "geodetic").
_WORD_FIELDS = frozenset({"action", "mode", "palette", "coordinate_system"})


def describe_params(fields: Mapping[str, Any]) -> str:
    """Parameters of a command in plain words: 'pan -5.00 deg/s tilt 0.00 deg/s'.

    Actions and modes come first, then values with units, then other words; the axis
    of specified_angle is left out because its value's name says it ('pitch -45.00 deg').
    """
    words: list[str] = []
    values: list[str] = []
    rest: list[str] = []
    for key, value in fields.items():
        if key in _META_FIELDS or key.endswith("_raw") or key == "axis":
            continue
        label, text = format_value(key, value)
        if key in ("action", "mode", "palette"):
            words.append(text)
        elif key in _WORD_FIELDS:
            rest.append(text)
        else:
            values.append(f"{label} {text}")
    return " ".join(words + values + rest)


def _own_text(event: Event) -> str:
    f = event.fields
    topic = event.topic
    if topic == TOPIC_COMMAND:
        name = str(f.get("name", "?"))
        if name == "unknown":
            return f"unknown command S_ID 0x{f.get('s_id', 0):02X} CMD 0x{f.get('cmd', 0):02X}"
        params = describe_params(f)
        return f"{name} {params}" if params else name
    if topic == TOPIC_DIAGNOSTICS:
        return f"{f.get('kind', '?')}: {f.get('detail', '')}"
    if topic == TOPIC_GIMBAL_ATTITUDE:
        return (
            f"attitude pitch {f.get('pitch_deg', 0):.2f} yaw {f.get('yaw_deg', 0):.2f} "
            f"motor yaw {f.get('motor_yaw_deg', 0):.2f} deg mode {f.get('control_mode', '?')}"
        )
    if topic == TOPIC_GIMBAL_RANGING:
        return "ranging " + describe_params(f)
    if topic == TOPIC_UAV_GPS:
        return f"uav gps {f.get('latitude_deg', 0):.7f} {f.get('longitude_deg', 0):.7f}"
    if topic == TOPIC_UAV_ALTITUDE:
        return f"uav altitude {f.get('altitude_m', 0):.2f} m"
    if topic == TOPIC_UAV_ATTITUDE:
        return (
            f"uav attitude pitch {f.get('pitch_deg', 0):.2f} roll {f.get('roll_deg', 0):.2f} "
            f"yaw {f.get('yaw_deg', 0):.2f} deg"
        )
    if topic == TOPIC_UAV_TEXT:
        return f"uav text {f.get('text', '')!r}"
    if topic == TOPIC_CAN_OTHER:
        return f"can 0x{f.get('can_id', 0):08X} [{f.get('dlc', 0)}] {f.get('data', '')}"
    return f"{topic} {describe_params(f)}"


def _load_renderer() -> Callable[[Event], str] | None:
    try:
        from analyzer.render import render_event  # type: ignore[import-not-found,unused-ignore]
    except ImportError:
        return None

    def render(event: Event) -> str:
        return str(render_event(event, color=False))

    return render


_RENDERER = _load_renderer()


def event_text(event: Event) -> str:
    """One line of plain words for an event (without the time column)."""
    text: str | None = None
    if _RENDERER is not None and event.topic == TOPIC_COMMAND:
        try:
            text = _RENDERER(event)
        except Exception:  # a renderer bug must not take the monitor down
            text = None
    if text is None:
        text = _own_text(event)
    direction = event.fields.get("direction")
    if direction:
        text = ("→ idu " if direction == TO_IDU else "← idu ") + text
    return text


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
