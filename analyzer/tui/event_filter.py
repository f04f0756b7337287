"""The filter typed by the user: topics, names and CAN IDs to show or hide."""

from __future__ import annotations

from dataclasses import dataclass, field

from analyzer.protocol.ids import (
    ALTITUDE_ID,
    CONTROL_ID,
    FEEDBACK_ID,
    GPS_ID,
    TEXT_END_ID,
    TEXT_ID,
    UAV_ATTITUDE_ID,
)
from analyzer.protocol.types import (
    TOPIC_COMMAND,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_GIMBAL_RANGING,
    TOPIC_UAV_ALTITUDE,
    TOPIC_UAV_ATTITUDE,
    TOPIC_UAV_GPS,
    TOPIC_UAV_TEXT,
    Event,
)

# The CAN IDs an event of each topic is decoded from.
TOPIC_IDS: dict[str, frozenset[int]] = {
    TOPIC_COMMAND: frozenset({CONTROL_ID}),
    TOPIC_GIMBAL_ATTITUDE: frozenset({FEEDBACK_ID}),
    TOPIC_GIMBAL_RANGING: frozenset({FEEDBACK_ID}),
    TOPIC_UAV_GPS: frozenset({GPS_ID}),
    TOPIC_UAV_ALTITUDE: frozenset({ALTITUDE_ID}),
    TOPIC_UAV_ATTITUDE: frozenset({UAV_ATTITUDE_ID}),
    TOPIC_UAV_TEXT: frozenset({TEXT_ID, TEXT_END_ID}),
}


def _parse_id(token: str) -> int | None:
    text = token.lower()
    if text.startswith("0x"):
        text = text[2:]
    elif not text.startswith("#"):
        return None
    else:
        text = text[1:]
    try:
        return int(text, 16)
    except ValueError:
        return None


@dataclass(frozen=True)
class FilterTerm:
    """One word of a filter: a topic prefix, a CAN ID or a name / text fragment."""

    text: str
    topic: str | None = None
    can_id: int | None = None

    @classmethod
    def parse(cls, token: str) -> FilterTerm:
        if token.startswith("/"):
            return cls(token, topic=token)
        can_id = _parse_id(token)
        if can_id is not None:
            return cls(token, can_id=can_id)
        return cls(token.lower())

    def matches_event(self, event: Event, line: str) -> bool:
        if self.topic is not None:
            return event.topic.startswith(self.topic)
        if self.can_id is not None:
            if event.fields.get("can_id") == self.can_id:
                return True
            return self.can_id in TOPIC_IDS.get(event.topic, ())
        name = event.fields.get("name") or event.fields.get("kind") or ""
        return self.text in str(name).lower() or self.text in line.lower()

    def matches_row(self, can_id: int | None, label: str, key: str) -> bool:
        if self.topic is not None:
            return False
        if self.can_id is not None:
            return can_id == self.can_id
        return self.text in label.lower() or self.text in key.lower()


@dataclass(frozen=True)
class EventFilter:
    """Space-separated terms: shown if any plain term matches and no '-' term does.

    ``/uav`` matches topics by prefix, ``0xF01`` (or ``#F01``) a CAN ID (events match
    the ID they are decoded from), anything else a command name, diagnostic kind or
    text in the line. ``-gimbal_control`` hides what it matches. Empty: show all.
    """

    text: str = ""
    include: tuple[FilterTerm, ...] = field(default=())
    exclude: tuple[FilterTerm, ...] = field(default=())

    @classmethod
    def parse(cls, text: str) -> EventFilter:
        include: list[FilterTerm] = []
        exclude: list[FilterTerm] = []
        for token in text.split():
            if token.startswith("-") and len(token) > 1:
                exclude.append(FilterTerm.parse(token[1:]))
            else:
                include.append(FilterTerm.parse(token))
        return cls(text.strip(), tuple(include), tuple(exclude))

    @property
    def active(self) -> bool:
        return bool(self.include or self.exclude)

    def matches_event(self, event: Event, line: str) -> bool:
        if self.include and not any(t.matches_event(event, line) for t in self.include):
            return False
        return not any(t.matches_event(event, line) for t in self.exclude)

    def matches_row(self, can_id: int | None, label: str, key: str) -> bool:
        """Rows of the ID table; topic terms do not hide rows."""
        row_terms = [t for t in self.include if t.topic is None]
        if row_terms and not any(t.matches_row(can_id, label, key) for t in row_terms):
            return False
        return not any(t.matches_row(can_id, label, key) for t in self.exclude)
