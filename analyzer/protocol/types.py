"""Value types shared by the whole analyzer: CAN frames, stream chunks and events."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

# Topics of the event contract.
TOPIC_COMMAND = "/gimbal/command"
TOPIC_GIMBAL_ATTITUDE = "/gimbal/attitude"
TOPIC_GIMBAL_RANGING = "/gimbal/ranging"
TOPIC_UAV_GPS = "/uav/gps"
TOPIC_UAV_ALTITUDE = "/uav/altitude"
TOPIC_UAV_ATTITUDE = "/uav/attitude"
TOPIC_UAV_TEXT = "/uav/text"
TOPIC_DIAGNOSTICS = "/diagnostics"
TOPIC_CAN_OTHER = "/can/other"
TOPIC_CAN_BUS_STATE = "/can/bus_state"  # a CAN controller's error state, from error frames
TOPIC_ANALYSIS_RESPONSE = "/analysis/response"  # findings of the response analysis
TOPIC_CHECK_STEPS = "/check/steps"  # verdicts of the bench check's steps
TOPIC_ARDUPILOT_MOUNT = "/ardupilot/mount"  # attitude an ArduPilot mount driver reported
TOPIC_ARDUPILOT_TARGETS = "/ardupilot/targets"  # what ArduPilot's mount library asked

TOPICS = (
    TOPIC_COMMAND,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_GIMBAL_RANGING,
    TOPIC_UAV_GPS,
    TOPIC_UAV_ALTITUDE,
    TOPIC_UAV_ATTITUDE,
    TOPIC_UAV_TEXT,
    TOPIC_DIAGNOSTICS,
    TOPIC_ANALYSIS_RESPONSE,
    TOPIC_CHECK_STEPS,
    TOPIC_CAN_BUS_STATE,
    TOPIC_ARDUPILOT_MOUNT,
    TOPIC_ARDUPILOT_TARGETS,
)

# Diagnostic kinds (the ``kind`` field of /diagnostics events).
CRC_MISMATCH = "crc_mismatch"
INCOMPLETE = "incomplete"
BAD_FRAME = "bad_frame"
BAD_LINE = "bad_line"
TEXT_UNTERMINATED = "text_unterminated"
GARBAGE = "garbage"
DUPLICATE = "duplicate"
BUS_ERROR = "bus_error"
LINK = "link"

DIAGNOSTIC_KINDS = (
    CRC_MISMATCH,
    INCOMPLETE,
    BAD_FRAME,
    BAD_LINE,
    TEXT_UNTERMINATED,
    GARBAGE,
    DUPLICATE,
    BUS_ERROR,
    LINK,
)

# Directions of a TCP / UART stream.
TO_IDU = "gs_to_idu"
FROM_IDU = "idu_to_gs"


# Frames and chunks are treated as immutable, but not frozen: a frozen dataclass costs
# about 2 us more to build, which is a third of the per-frame budget of `decode`.
@dataclass(slots=True)
class CanFrame:
    """One CAN frame as seen on a bus or in a log file."""

    time: float
    can_id: int
    data: bytes
    extended: bool = True
    channel: str = ""
    is_remote: bool = False
    is_error: bool = False
    is_fd: bool = False
    direction: str = ""  # "rx" / "tx" when the log says so
    remote_dlc: int = 0  # the DLC a remote frame requests (it carries no data)

    @property
    def dlc(self) -> int:
        """The frame's DLC: the requested length of a remote frame, else its data length."""
        return self.remote_dlc if self.is_remote else len(self.data)


@dataclass(slots=True)
class StreamChunk:
    """Bytes read from a TCP or UART stream in one go."""

    time: float
    data: bytes
    source: str = "stream"
    direction: str = ""  # TO_IDU / FROM_IDU / "" when unknown


@dataclass(slots=True)
class Event:
    """A decoded message or a diagnostic; becomes one JSON object.

    ``topic`` says what it is (``/gimbal/command``, ``/gimbal/attitude``, ``/uav/gps``,
    ``/diagnostics``, ...), ``time`` when (seconds), ``source`` where from (a CAN
    channel, a stream), ``fields`` the decoded values in the units of their names
    (``pan_speed_dps``, ``yaw_deg``; a labelled value with its number in ``<name>_code``)
    and ``warnings`` what looked wrong. ``to_dict()`` is the JSON line ``decode --json``
    prints (``schemas/`` holds each topic's JSON Schema).

    >>> from analyzer import Decoder, encode
    >>> [event] = Decoder().feed_can(0x00000F01, encode("zoom", action="stop"), 3.0, "can0")
    >>> event.to_dict()  # doctest: +NORMALIZE_WHITESPACE
    {'topic': '/gimbal/command', 'time': 3.0, 'source': 'can0', 'warnings': [], 's_id': 15,
     'cmd': 18, 'name': 'zoom', 'component': 'gimbal', 'raw': '0F 12 03 00 00 00 00 00',
     'action': 'stop', 'action_code': 3}
    """

    topic: str
    time: float
    source: str
    fields: dict[str, Any] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """The event as one JSON object: topic, time, source, warnings, then the fields."""
        out: dict[str, Any] = {
            "topic": self.topic,
            "time": self.time,
            "source": self.source,
            "warnings": list(self.warnings),
        }
        out.update(self.fields)
        return out

    @classmethod
    def from_dict(cls, obj: dict[str, Any]) -> Event:
        """The event of a JSON object ``to_dict`` made (a line of ``decode --json``)."""
        rest = {k: v for k, v in obj.items() if k not in ("topic", "time", "source", "warnings")}
        return cls(
            topic=str(obj["topic"]),
            time=float(obj["time"]),
            source=str(obj.get("source", "")),
            fields=rest,
            warnings=list(obj.get("warnings", [])),
        )


def hexstr(data: bytes) -> str:
    """Bytes as upper-case hex pairs separated by spaces, as the vendor document writes them."""
    return data.hex(" ").upper()


def diagnostic(
    time: float,
    source: str,
    kind: str,
    detail: str,
    raw: bytes = b"",
    **extra: Any,
) -> Event:
    """Build a /diagnostics event."""
    fields: dict[str, Any] = {"kind": kind, "detail": detail, "raw": hexstr(raw)}
    fields["byte_count"] = len(raw)
    fields.update(extra)
    return Event(TOPIC_DIAGNOSTICS, time, source, fields)
