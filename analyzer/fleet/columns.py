"""Arrow schemas of the fleet tables, from the topic schemas (command table and layouts)."""

from __future__ import annotations

from functools import cache
from typing import Any

import pyarrow as pa

from analyzer.analysis.findings import HEALTH_VERDICTS, VERDICTS
from analyzer.protocol.types import (
    DIAGNOSTIC_KINDS,
    TOPIC_ANALYSIS_RESPONSE,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_GIMBAL_RANGING,
    TOPIC_UAV_ALTITUDE,
    TOPIC_UAV_ATTITUDE,
    TOPIC_UAV_GPS,
    TOPIC_UAV_TEXT,
)

# topic -> table name
TOPIC_TABLES: dict[str, str] = {
    TOPIC_COMMAND: "commands",
    TOPIC_GIMBAL_ATTITUDE: "attitude",
    TOPIC_GIMBAL_RANGING: "ranging",
    TOPIC_UAV_GPS: "uav_gps",
    TOPIC_UAV_ALTITUDE: "uav_altitude",
    TOPIC_UAV_ATTITUDE: "uav_attitude",
    TOPIC_UAV_TEXT: "uav_text",
    TOPIC_DIAGNOSTICS: "diagnostics",
    TOPIC_ANALYSIS_RESPONSE: "findings",
}
RECORDINGS = "recordings"
TABLES: tuple[str, ...] = (RECORDINGS, *TOPIC_TABLES.values())

TIME = pa.timestamp("us", tz="UTC")
EXTRA = "extra"  # fields an event carries that its schema does not name, as JSON
# Columns every event table starts with: which recording (by name and content) and when.
KEY_FIELDS: tuple[pa.Field, ...] = (
    pa.field("recording", pa.string(), nullable=False),
    pa.field("content_hash", pa.string(), nullable=False),
    pa.field("time", TIME),
    pa.field("source", pa.string()),
)
# The one unit of crc_error_rate in every table, answer, plot and reason: a fraction.
CRC_RATE_UNIT = "errors per CRC-checked message (0.01 = 1 in 100)"
# Findings may carry these (the yaw reference and why it was chosen) when the analysis has them.
FINDING_EXTRAS = {"yaw_reference": "string", "reference_reason": "string"}

_JSON_TYPES: dict[str, pa.DataType] = {
    "string": pa.string(),
    "integer": pa.int64(),
    "number": pa.float64(),
    "boolean": pa.bool_(),
    "array": pa.list_(pa.string()),
}
_SKIPPED = frozenset({"topic", "time", "source"})


def arrow_type(prop: dict[str, Any]) -> pa.DataType:
    """The Arrow type of one JSON Schema property (a string when the schema says nothing)."""
    kind = prop.get("type", "string")
    return _JSON_TYPES.get(kind if isinstance(kind, str) else "string", pa.string())


@cache
def event_schema(topic: str) -> pa.Schema:
    """The columns of the table of ``topic``: key columns, the topic's fields, then ``extra``."""
    from analyzer.protocol.schema import topic_schemas

    props: dict[str, Any] = dict(topic_schemas()[topic]["properties"])
    if topic == TOPIC_ANALYSIS_RESPONSE:
        for name, kind in FINDING_EXTRAS.items():
            props.setdefault(name, {"type": kind})
    fields = list(KEY_FIELDS)
    fields += [pa.field(name, arrow_type(p)) for name, p in props.items() if name not in _SKIPPED]
    fields.append(pa.field(EXTRA, pa.string()))
    return pa.schema(fields)


def diagnostic_column(kind: str) -> str:
    return f"diag_{kind}"


def verdict_column(verdict: str) -> str:
    """The column counting the commands' findings of one verdict."""
    return f"findings_{verdict}"


def health_column(health: str) -> str:
    """The column counting the feedback's findings (minutes, silences) of one health word."""
    return f"feedback_{health}"


def recordings_schema(tags: list[str]) -> pa.Schema:
    """One row per input: its tags, where it came from, and the figures of its run."""
    fields = [
        pa.field("recording", pa.string(), nullable=False),
        pa.field("content_hash", pa.string(), nullable=False),
        *(pa.field(tag, pa.string()) for tag in tags),
        pa.field("path", pa.string()),
        pa.field("size_bytes", pa.int64()),
        pa.field("source", pa.string()),
        pa.field("format", pa.string()),
        pa.field("start", TIME),
        pa.field("end", TIME),
        pa.field("duration_s", pa.float64()),
        pa.field("frames", pa.int64()),
        pa.field("chunks", pa.int64()),
        pa.field("bytes", pa.int64()),
        pa.field("events", pa.int64()),
        pa.field("commands", pa.int64()),
        pa.field("feedback_messages", pa.int64()),
        pa.field("feedback_rate_hz", pa.float64()),
        pa.field("crc_checked", pa.int64()),
        pa.field("crc_errors", pa.int64()),
        pa.field("crc_error_rate", pa.float64(), metadata={"unit": CRC_RATE_UNIT}),
        pa.field("gaps", pa.int64()),
        pa.field("longest_gap_s", pa.float64()),
        pa.field("bus_worst_state", pa.string()),  # of the CAN controller, from error frames
        pa.field("bus_worst_time", TIME),
        pa.field("diagnostics", pa.int64()),
        *(pa.field(diagnostic_column(k), pa.int64()) for k in DIAGNOSTIC_KINDS),
        pa.field("findings", pa.int64()),
        *(pa.field(verdict_column(v), pa.int64()) for v in VERDICTS),
        *(pa.field(health_column(h), pa.int64()) for h in HEALTH_VERDICTS),
        pa.field("analyzer_version", pa.string()),
        pa.field("error", pa.string()),
        pa.field("notes", pa.list_(pa.string())),
    ]
    return pa.schema(fields)


def empty_table(name: str) -> pa.Table:
    """A table of no rows with the columns of ``name`` (no tags for recordings)."""
    if name == RECORDINGS:
        return recordings_schema([]).empty_table()
    topic = next(t for t, n in TOPIC_TABLES.items() if n == name)
    return event_schema(topic).empty_table()
