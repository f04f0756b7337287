"""One readable line per event: aligned time, source, topic and name, then values with units."""

from __future__ import annotations

from typing import Any

from analyzer.protocol.fields import CODE_SUFFIX
from analyzer.protocol.response_fields import verdict_word
from analyzer.protocol.types import (
    FROM_IDU,
    TO_IDU,
    TOPIC_ANALYSIS_RESPONSE,
    TOPIC_CAN_BUS_STATE,
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
from analyzer.terminal_text import printable
from analyzer.timefmt import UTC, TimeZone

WHERE_WIDTH = 17
TOPIC_WIDTH = 17
LABEL_WIDTH = 16
RAW_SHOWN = 24  # bytes of a diagnostic's raw data shown on its line

DIRECTION_WORDS = {TO_IDU: "gs->idu", FROM_IDU: "idu->gs"}

# Short names of the topics that carry no name field.
TOPIC_LABELS = {
    TOPIC_GIMBAL_ATTITUDE: "gimbal attitude",
    TOPIC_GIMBAL_RANGING: "ranging",
    TOPIC_UAV_GPS: "gps",
    TOPIC_UAV_ALTITUDE: "altitude",
    TOPIC_UAV_ATTITUDE: "uav attitude",
    TOPIC_UAV_TEXT: "text",
    TOPIC_CAN_OTHER: "other frame",
    TOPIC_CAN_BUS_STATE: "bus state",
}

# Field-name suffix -> unit words; the suffix is dropped from the shown name.
UNIT_SUFFIXES: tuple[tuple[str, str], ...] = (
    ("_speed_dps", "deg/s"),
    ("_dps", "deg/s"),
    ("_deg", "deg"),
    ("_pct", "%"),
    ("_m", "m"),
    ("_s", "s"),
)
PRECISE = frozenset({"latitude_deg", "longitude_deg"})  # shown with 7 decimals

# Fields that identify the event or say where it came from, not values.
META_FIELDS = frozenset(
    {
        "s_id",
        "cmd",
        "name",
        "component",
        "raw",
        "transport",
        "direction",
        "crc_set",
        "byte_count",
        "start_time",
        "frames",
    }
)

# Command fields whose label alone says enough, shown before / after the values.
LEADING_WORDS = frozenset({"action", "mode", "palette"})
TRAILING_WORDS = frozenset({"coordinate_system"})
# Fields shown after the values that change, so narrow views keep the angles.
TRAILING_FIELDS = {TOPIC_GIMBAL_ATTITUDE: frozenset({"gimbal_type", "tracking", "control_mode"})}

# ANSI styles, used only when asked for colour.
_RESET = "\033[0m"
_STYLES = {
    "time": "\033[2m",
    "where": "\033[34m",
    "topic": "\033[36m",
    "label": "\033[1m",
    "diagnostic": "\033[1;31m",
    "warning": "\033[33m",
}


def format_time(t: float, zone: TimeZone = UTC) -> str:
    """``HH:MM:SS.mmm`` in UTC with ``Z`` (or, in ``zone`` local, local time with its
    offset) for Unix times, else seconds with milliseconds."""
    return zone.format_clock(t)


def short_source(source: str) -> str:
    """``tcp:10.0.0.5:50211-192.168.42.200:2000`` -> ``tcp:50211`` (the client's port)."""
    if source.startswith("tcp:") and "-" in source:
        client = source[4:].split("-", 1)[0]
        port = client.rsplit(":", 1)[-1]
        if port.isdigit():
            generation = source.rsplit("#", 1)[1] if "#" in source else ""
            return f"tcp:{port}" + (f"#{generation}" if generation else "")
    return source


def where(event: Event) -> str:
    """Source of an event (TCP flows by client port), with the direction for streams."""
    direction = event.fields.get("direction")
    words = DIRECTION_WORDS.get(direction, direction) if isinstance(direction, str) else ""
    source = short_source(event.source)
    return f"{source} {words}" if words else source


def label(event: Event) -> str:
    """The name column: command name, diagnostic kind, or a short topic name."""
    if event.topic == TOPIC_DIAGNOSTICS:
        return str(event.fields.get("kind", "diagnostic")).upper()
    name = event.fields.get("name")
    if event.topic == TOPIC_COMMAND and name:
        return str(name)
    return TOPIC_LABELS.get(event.topic, event.topic.rsplit("/", 1)[-1])


def value_words(key: str, value: Any, fields: dict[str, Any], zone: TimeZone = UTC) -> str:
    """One field as ``name value unit``, e.g. ``pan -5.00 deg/s``."""
    shown, unit = key, ""
    for suffix, words in UNIT_SUFFIXES:
        if key.endswith(suffix) and len(key) > len(suffix):
            shown, unit = key[: -len(suffix)], words
            break
    shown = shown.replace("_", " ")
    if isinstance(value, bool):
        text = "yes" if value else "no"
    elif key.endswith("_at") and isinstance(value, (int, float)):
        text = format_time(value, zone)  # a moment (``observed_at``): a clock time, not seconds
    elif isinstance(value, float):
        text = f"{value:.7f}" if key in PRECISE else f"{value:.2f}"
    else:
        text = str(value)
    return f"{shown} {text} {unit}".rstrip()


def describe(event: Event, zone: TimeZone = UTC) -> str:
    """The values of an event in plain words (no time, source, topic or name columns);
    the moments among them in ``zone``."""
    fields = event.fields
    topic = event.topic
    if topic == TOPIC_DIAGNOSTICS:
        return _diagnostic_words(fields)
    if topic == TOPIC_UAV_TEXT:
        return repr(str(fields.get("text", "")))
    if topic == TOPIC_CAN_BUS_STATE:
        return bus_state_words(fields, zone)
    if topic == TOPIC_CAN_OTHER:
        return _other_frame_words(fields)
    return _field_words(topic, fields, zone)


def _diagnostic_words(fields: dict[str, Any]) -> str:
    """A diagnostic's detail, and the first bytes of what it is about."""
    text = str(fields.get("detail", ""))
    raw = str(fields.get("raw", ""))
    if raw:
        parts = raw.split()
        more = f" ... ({len(parts)} bytes)" if len(parts) > RAW_SHOWN else ""
        text += f"  raw {' '.join(parts[:RAW_SHOWN])}{more}"
    return text


def _other_frame_words(fields: dict[str, Any]) -> str:
    """Another device's CAN frame: its ID, length and data."""
    can_id = int(fields.get("can_id", 0))
    ident = f"0x{can_id:08X}" if fields.get("extended", True) else f"0x{can_id:03X}"
    if fields.get("remote"):
        return f"id {ident} [{fields.get('dlc', 0)}] remote request"
    return f"id {ident} [{fields.get('dlc', 0)}] {fields.get('data', '')}".rstrip()


def _field_words(topic: str, fields: dict[str, Any], zone: TimeZone) -> str:
    """A command's, a message's or a finding's fields in words: those that say it alone
    first, then each value with its name and unit, then the trailing ones."""
    head: list[str] = []
    words: list[str] = []
    tail: list[str] = []
    command = topic == TOPIC_COMMAND
    if command:
        if fields.get("component") not in (None, "gimbal"):
            head.append(str(fields["component"]))
        if fields.get("name") == "unknown":
            words.append(f"s_id 0x{fields.get('s_id', 0):02X} cmd 0x{fields.get('cmd', 0):02X}")
            words.append(f"raw {fields.get('raw', '')}")
    trailing = TRAILING_FIELDS.get(topic, ())
    for key, value in fields.items():
        if key in META_FIELDS or (key.endswith(CODE_SUFFIX) and key[: -len(CODE_SUFFIX)] in fields):
            continue  # the label says it; the number stays in the JSON
        said_alone = command and isinstance(value, str)
        if said_alone and key in LEADING_WORDS:
            head.append(value)  # "zoom_in", "single", "iron_red" say it alone
        elif said_alone and key in TRAILING_WORDS:
            tail.append(value)
        elif key in trailing:
            tail.append(value_words(key, value, fields, zone))
        elif said_alone and key == "axis":
            continue  # the value's own name says it: "pitch -45.00 deg"
        elif topic == TOPIC_ANALYSIS_RESPONSE and key == "verdict":
            words.append(f"verdict {verdict_word(fields)}")  # a gap is LOST, not NOT OBEYED
        else:
            words.append(value_words(key, value, fields, zone))
    return "  ".join(head + words + tail)


def bus_state_words(fields: dict[str, Any], zone: TimeZone = UTC) -> str:
    """``error-passive since 22:13:20.000Z  tx errors 128  rx errors 136  6 error frames``."""
    words = [str(fields.get("state", "?"))]
    since = fields.get("since")
    if isinstance(since, (int, float)):
        words[0] += f" since {format_time(since, zone)}"
    if "tx_errors" in fields:
        words.append(f"tx errors {fields['tx_errors']}  rx errors {fields.get('rx_errors')}")
    words.append(f"{fields.get('error_frames', 0)} error frames")
    return "  ".join(words)


def describe_event(event: Event, zone: TimeZone = UTC) -> str:
    """Name and values in plain words, e.g. ``gimbal_control pan -5.00 deg/s tilt 0.00 deg/s``."""
    text = describe(event, zone)
    return printable(f"{label(event)} {text}".rstrip())


def render_event(event: Event, color: bool = False, zone: TimeZone = UTC) -> str:
    """One aligned line: time (in ``zone``), source (and direction), topic, name, values,
    warnings."""
    diagnostic = event.topic == TOPIC_DIAGNOSTICS
    # Every part may hold text from the input (channel names, recorded topics, text
    # messages): control characters are escaped before anything reaches the terminal.
    columns = [
        (format_time(event.time, zone).rjust(zone.clock_width), "time"),
        (printable(where(event)).ljust(WHERE_WIDTH), "where"),
        (printable(event.topic).ljust(TOPIC_WIDTH), "topic"),
        (printable(label(event)).ljust(LABEL_WIDTH), "diagnostic" if diagnostic else "label"),
    ]
    try:
        body = describe(event, zone)
    except (TypeError, ValueError):  # fields of an unexpected type: show them as they are
        body = "  ".join(f"{k} {v}" for k, v in event.fields.items())
    body = printable(body)
    warnings = printable("; ".join(str(w) for w in event.warnings))
    if not color:
        line = " ".join(text for text, _ in columns) + " " + body
        if warnings:
            line = f"{line.rstrip()}  ! {warnings}"
        return line.rstrip()
    parts = [f"{_STYLES[style]}{text}{_RESET}" for text, style in columns]
    line = " ".join(parts) + " " + (_paint(body, "diagnostic") if diagnostic else body)
    if warnings:
        line = f"{line.rstrip()}  {_paint('! ' + warnings, 'warning')}"
    return line.rstrip()


def _paint(text: str, style: str) -> str:
    return f"{_STYLES[style]}{text}{_RESET}" if text else text
