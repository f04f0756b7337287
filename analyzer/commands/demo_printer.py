"""What `gimbal-analyzer demo --no-tui` prints: one plain line per event, UAV status thinned out."""

from __future__ import annotations

from collections.abc import Callable
from typing import IO

from analyzer.pipeline import Batch
from analyzer.protocol.types import (
    TOPIC_COMMAND,
    TOPIC_UAV_ALTITUDE,
    TOPIC_UAV_ATTITUDE,
    TOPIC_UAV_GPS,
    Event,
)
from analyzer.timefmt import UTC, TimeZone

QUIET_TOPICS = frozenset({TOPIC_UAV_GPS, TOPIC_UAV_ALTITUDE, TOPIC_UAV_ATTITUDE})
QUIET_EVERY = 1.0  # plain output: UAV status lines at most once a second per topic


class DemoPrinter:
    """Sink printing each event as one plain line; UAV status thinned out unless ``everything``."""

    def __init__(self, stream: IO[str], *, everything: bool = False, zone: TimeZone = UTC) -> None:
        self.stream = stream
        self.everything = everything
        self.hidden = 0
        self._last: dict[str, float] = {}
        self._last_command = ""
        self._render: Callable[[Event], str] = _renderer(zone)

    def handle(self, batch: Batch) -> None:
        lines = [self._render(e) for e in batch.events if self._shown(e)]
        if lines:
            self.stream.write("\n".join(lines) + "\n")
            self.stream.flush()

    def _shown(self, event: Event) -> bool:
        if self.everything:
            return True
        if event.topic in QUIET_TOPICS:
            if event.time - self._last.get(event.topic, -1e9) < QUIET_EVERY:
                self.hidden += 1
                return False
            self._last[event.topic] = event.time
        elif event.topic == TOPIC_COMMAND:
            raw = str(event.fields.get("raw", ""))
            last = self._last.get(TOPIC_COMMAND, -1e9)
            if raw == self._last_command and event.time - last < QUIET_EVERY:
                self.hidden += 1
                return False
            self._last_command = raw
            self._last[TOPIC_COMMAND] = event.time
        return True

    def close(self) -> None:
        self.stream.flush()


def _renderer(zone: TimeZone) -> Callable[[Event], str]:
    """Each event as a line, its time in ``zone``."""
    try:
        from analyzer.render import render_event
    except ImportError:
        return lambda event: _plain(event, zone)
    return lambda event: render_event(event, color=False, zone=zone)


def _plain(event: Event, zone: TimeZone) -> str:
    from analyzer.sim.engine import describe_command, format_fields

    stamp = zone.format_clock(event.time)
    if event.topic == TOPIC_COMMAND:
        text = describe_command(event.fields)
    else:
        text = format_fields(event.fields)
    warnings = f"  !! {'; '.join(event.warnings)}" if event.warnings else ""
    return f"{stamp} {event.topic:<17} {text}{warnings}"
