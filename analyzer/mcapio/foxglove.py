"""Foxglove views of events: target and UAV positions as LocationFix, diagnostics as Log,
where the gimbal points as transforms, a 3D scene and overlays on the camera's pictures."""

from __future__ import annotations

import math
from typing import Any

from analyzer.mcapio.log_time import timestamp
from analyzer.mcapio.scene_views import (
    ANNOTATIONS_SCHEMA,
    SCENE_SCHEMAS,
    SceneViews,
    is_annotation_topic,
)
from analyzer.protocol.types import (
    BUS_ERROR,
    LINK,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_RANGING,
    TOPIC_UAV_ALTITUDE,
    TOPIC_UAV_GPS,
    Event,
)
from analyzer.scene.state import INPUT_TOPICS as SCENE_INPUT_TOPICS
from analyzer.scene.state import SCENE_COMMANDS

LOCATION_FIX = "foxglove.LocationFix"
LOG = "foxglove.Log"

TOPIC_UAV_FIX = "/uav/gps/fix"
TOPIC_TARGET_FIX = "/gimbal/ranging/fix"
TOPIC_DIAGNOSTICS_LOG = "/diagnostics/log"

# foxglove.LogLevel
LOG_UNKNOWN, LOG_DEBUG, LOG_INFO, LOG_WARNING, LOG_ERROR, LOG_FATAL = range(6)
# foxglove.PositionCovarianceType
COVARIANCE_UNKNOWN = 0

TIME_SCHEMA: dict[str, Any] = {
    "type": "object",
    "title": "time",
    "properties": {
        "sec": {"type": "integer", "minimum": 0},
        "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999},
    },
}

LOCATION_FIX_SCHEMA: dict[str, Any] = {
    "title": LOCATION_FIX,
    "description": "A navigation satellite fix for any Global Navigation Satellite System",
    "type": "object",
    "properties": {
        "timestamp": {**TIME_SCHEMA, "description": "Timestamp of the message"},
        "frame_id": {"type": "string", "description": "Frame for the sensor"},
        "latitude": {"type": "number", "description": "Latitude in degrees"},
        "longitude": {"type": "number", "description": "Longitude in degrees"},
        "altitude": {"type": "number", "description": "Altitude in meters"},
        "position_covariance": {
            "type": "array",
            "items": {"type": "number"},
            "minItems": 9,
            "maxItems": 9,
            "description": "Position covariance (m^2), ENU, row-major",
        },
        "position_covariance_type": {
            "title": "foxglove.PositionCovarianceType",
            "description": "Type of position covariance",
            "oneOf": [
                {"title": "UNKNOWN", "const": 0},
                {"title": "APPROXIMATED", "const": 1},
                {"title": "DIAGONAL_KNOWN", "const": 2},
                {"title": "KNOWN", "const": 3},
            ],
        },
    },
    "required": [
        "timestamp",
        "frame_id",
        "latitude",
        "longitude",
        "altitude",
        "position_covariance",
        "position_covariance_type",
    ],
}

LOG_SCHEMA: dict[str, Any] = {
    "title": LOG,
    "description": "A log message",
    "type": "object",
    "properties": {
        "timestamp": {**TIME_SCHEMA, "description": "Timestamp of log message"},
        "level": {
            "title": "foxglove.LogLevel",
            "description": "Log level",
            "oneOf": [
                {"title": "UNKNOWN", "const": LOG_UNKNOWN},
                {"title": "DEBUG", "const": LOG_DEBUG},
                {"title": "INFO", "const": LOG_INFO},
                {"title": "WARNING", "const": LOG_WARNING},
                {"title": "ERROR", "const": LOG_ERROR},
                {"title": "FATAL", "const": LOG_FATAL},
            ],
        },
        "message": {"type": "string", "description": "Log message"},
        "name": {"type": "string", "description": "Process or node name"},
        "file": {"type": "string", "description": "Filename"},
        "line": {"type": "integer", "minimum": 0, "description": "Line number in the file"},
    },
    "required": ["timestamp", "level", "message", "name", "file", "line"],
}

VIEW_SCHEMAS: dict[str, tuple[str, dict[str, Any]]] = {
    TOPIC_UAV_FIX: (LOCATION_FIX, LOCATION_FIX_SCHEMA),
    TOPIC_TARGET_FIX: (LOCATION_FIX, LOCATION_FIX_SCHEMA),
    TOPIC_DIAGNOSTICS_LOG: (LOG, LOG_SCHEMA),
    **SCENE_SCHEMAS,
}

# Topics whose events have a Foxglove view (UAV altitude only feeds the UAV fix).
VIEW_INPUT_TOPICS = frozenset(
    {TOPIC_UAV_ALTITUDE, TOPIC_UAV_GPS, TOPIC_GIMBAL_RANGING, TOPIC_DIAGNOSTICS}
    | SCENE_INPUT_TOPICS
)


def view_schema(topic: str) -> tuple[str, dict[str, Any]]:
    """Schema name and JSON Schema of a view topic (a camera's /annotations included)."""
    known = VIEW_SCHEMAS.get(topic)
    if known is not None:
        return known
    if is_annotation_topic(topic):
        return ANNOTATIONS_SCHEMA
    raise KeyError(topic)


_ZERO_COVARIANCE = [0.0] * 9
# Link states (sources' link events) that are good news; the others are warnings.
_GOOD_LINK_STATES = frozenset({"open", "connected", "gs_connected", "listening"})


def _number(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    number = float(value)
    return number if math.isfinite(number) else None


def _fix(event: Event, frame_id: str, altitude: float) -> dict[str, Any] | None:
    lat = _number(event.fields.get("latitude_deg"))
    lon = _number(event.fields.get("longitude_deg"))
    if lat is None or lon is None or not (-90 <= lat <= 90 and -180 <= lon <= 180):
        return None
    if lat == 0 and lon == 0:  # 0/0 is what a source sends before it has a fix
        return None
    return {
        "timestamp": timestamp(event.time),
        "frame_id": frame_id,
        "latitude": lat,
        "longitude": lon,
        "altitude": altitude,
        "position_covariance": _ZERO_COVARIANCE,
        "position_covariance_type": COVARIANCE_UNKNOWN,
    }


def log_level(event: Event) -> int:
    """Foxglove log level of a diagnostic."""
    kind = event.fields.get("kind")
    if kind == BUS_ERROR:
        return _bus_error_level(event.fields)
    if kind == LINK:
        state = str(event.fields.get("state", "")).lower()
        if state == "failed":  # the capture stopped on this failure
            return LOG_ERROR
        return LOG_INFO if state in _GOOD_LINK_STATES else LOG_WARNING
    return LOG_WARNING


def _bus_error_level(fields: dict[str, Any]) -> int:
    """A recovery is good news; an error-passive or bus-off controller is an error."""
    state = fields.get("bus_state")
    if state in (None, "error-passive", "bus-off"):
        return LOG_ERROR
    recovered = "restarted-after-bus-off" in (fields.get("classes") or ()) or (
        "back-to-error-active" in (fields.get("controller") or ())
    )
    return LOG_INFO if recovered and state == "error-active" else LOG_WARNING


def log_message(event: Event) -> dict[str, Any]:
    kind = event.fields.get("kind", "diagnostic")
    text = f"{kind}: {event.fields.get('detail', '')}"
    raw = event.fields.get("raw")
    if raw:
        text += f" [{raw}]"
    return {
        "timestamp": timestamp(event.time),
        "level": log_level(event),
        "message": text,
        "name": event.source,
        "file": "",
        "line": 0,
    }


class FoxgloveViews:
    """Turns events into Foxglove messages; keeps the last UAV altitude for the UAV fix, and
    the gimbal's state for the transforms, the scene and the overlays (``scene``)."""

    def __init__(self) -> None:
        self.uav_altitude_m = 0.0
        self.scene = SceneViews()

    def views(self, event: Event) -> list[tuple[str, dict[str, Any]]]:
        """(topic, message) pairs to publish for one event (most events give none)."""
        topic = event.topic
        if topic == TOPIC_COMMAND and event.fields.get("name") not in SCENE_COMMANDS:
            return []  # a command that changes nothing drawn: most of a busy bus's traffic
        out = self.scene.views(event)
        if topic == TOPIC_UAV_ALTITUDE:
            altitude = _number(event.fields.get("altitude_m"))
            if altitude is not None:
                self.uav_altitude_m = altitude
        elif topic == TOPIC_UAV_GPS:
            fix = _fix(event, "uav", self.uav_altitude_m)
            if fix is not None:
                out.append((TOPIC_UAV_FIX, fix))
        elif topic == TOPIC_GIMBAL_RANGING:
            fix = (
                None if event.fields.get("success") is False else _fix(event, "ranging_target", 0.0)
            )
            if fix is not None:
                out.append((TOPIC_TARGET_FIX, fix))
        elif topic == TOPIC_DIAGNOSTICS:
            out.append((TOPIC_DIAGNOSTICS_LOG, log_message(event)))
        return out
