"""What the error frames of a run say about each CAN bus: worst state and when, counts by class.

Folded from the ``bus_error`` diagnostics (so a recording's events give the same figures
as the run that made it), kept in the run's :class:`analyzer.tally.Tally`, and read by
``decode --summary``, ``info``, the monitor and ``record``'s status line (in the same
words, ``status_words``), the report and the fleet table.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

from analyzer.protocol.bus_state import ERROR_ACTIVE, LEVELS
from analyzer.protocol.lru import MAX_SOURCES
from analyzer.protocol.types import BUS_ERROR, TOPIC_DIAGNOSTICS, Event
from analyzer.timefmt import UTC, TimeZone


def _level(state: str) -> int:
    return LEVELS.get(state, 0)


@dataclass
class ChannelBus:
    """The error frames of one channel."""

    state: str = ERROR_ACTIVE  # after the last error frame
    worst: str = ERROR_ACTIVE
    worst_time: float | None = None  # when the worst state was first reached
    last_time: float | None = None
    error_frames: int = 0
    malformed: int = 0
    tx_errors_max: int = 0
    rx_errors_max: int = 0
    classes: Counter[str] = field(default_factory=Counter)
    controller: Counter[str] = field(default_factory=Counter)
    protocol: Counter[str] = field(default_factory=Counter)
    locations: Counter[str] = field(default_factory=Counter)
    transceiver: Counter[str] = field(default_factory=Counter)

    def add(self, event: Event) -> None:
        fields = event.fields
        self.error_frames += 1
        self.last_time = event.time
        state = str(fields.get("bus_state", self.state))
        self.state = state if state in LEVELS else self.state
        if self.worst_time is None or _level(self.state) > _level(self.worst):
            self.worst, self.worst_time = self.state, event.time
        if fields.get("malformed"):
            self.malformed += 1
        for name, counter in (
            ("classes", self.classes),
            ("controller", self.controller),
            ("protocol", self.protocol),
        ):
            values = fields.get(name)
            if isinstance(values, list):
                counter.update(str(v) for v in values)
        classes = fields.get("classes")
        if fields.get("location") is not None and "protocol-violation" in (classes or ()):
            self.locations[str(fields["location"])] += 1
        if fields.get("transceiver") is not None:
            self.transceiver[str(fields["transceiver"])] += 1
        tx, rx = fields.get("tx_errors"), fields.get("rx_errors")
        if isinstance(tx, int) and isinstance(rx, int):
            self.tx_errors_max = max(self.tx_errors_max, tx)
            self.rx_errors_max = max(self.rx_errors_max, rx)

    def figures(self) -> dict[str, Any]:
        return {
            "state": self.state,
            "worst_state": self.worst,
            "worst_time": self.worst_time,
            "last_time": self.last_time,
            "error_frames": self.error_frames,
            "malformed": self.malformed,
            "tx_errors_max": self.tx_errors_max,
            "rx_errors_max": self.rx_errors_max,
            "classes": dict(sorted(self.classes.items())),
            "controller": dict(sorted(self.controller.items())),
            "protocol": dict(sorted(self.protocol.items())),
            "locations": dict(sorted(self.locations.items())),
            "transceiver": dict(sorted(self.transceiver.items())),
        }

    @classmethod
    def from_figures(cls, data: dict[str, Any]) -> ChannelBus:
        def counts(name: str) -> Counter[str]:
            return Counter({str(k): int(v) for k, v in dict(data.get(name) or {}).items()})

        worst_time = data.get("worst_time")
        last_time = data.get("last_time")
        return cls(
            state=str(data.get("state", ERROR_ACTIVE)),
            worst=str(data.get("worst_state", ERROR_ACTIVE)),
            worst_time=None if worst_time is None else float(worst_time),
            last_time=None if last_time is None else float(last_time),
            error_frames=int(data.get("error_frames", 0)),
            malformed=int(data.get("malformed", 0)),
            tx_errors_max=int(data.get("tx_errors_max", 0)),
            rx_errors_max=int(data.get("rx_errors_max", 0)),
            classes=counts("classes"),
            controller=counts("controller"),
            protocol=counts("protocol"),
            locations=counts("locations"),
            transceiver=counts("transceiver"),
        )


@dataclass
class BusFigures:
    """Every channel's error frames (at most MAX_SOURCES channels; more are only counted)."""

    channels: dict[str, ChannelBus] = field(default_factory=dict)
    untracked: int = 0  # error frames of channels beyond the first MAX_SOURCES

    def __bool__(self) -> bool:
        return bool(self.channels or self.untracked)

    def add_events(self, events: Iterable[Event]) -> None:
        """Fold the bus_error diagnostics among ``events``."""
        for event in events:
            if event.topic != TOPIC_DIAGNOSTICS or event.fields.get("kind") != BUS_ERROR:
                continue
            bus = self.channels.get(event.source)
            if bus is None:
                if len(self.channels) >= MAX_SOURCES:
                    self.untracked += 1
                    continue
                bus = self.channels[event.source] = ChannelBus()
            bus.add(event)

    @property
    def error_frames(self) -> int:
        return self.untracked + sum(bus.error_frames for bus in self.channels.values())

    def worst(self) -> tuple[str, float | None, str] | None:
        """(state, when first reached, channel) of the worst state any channel reached."""
        if not self.channels:
            return None
        channel, bus = max(
            self.channels.items(),
            key=lambda item: (_level(item[1].worst), -(item[1].worst_time or 0.0)),
        )
        return bus.worst, bus.worst_time, channel

    def classes(self) -> Counter[str]:
        """Error frames by class, every channel together."""
        total: Counter[str] = Counter()
        for bus in self.channels.values():
            total.update(bus.classes)
        return total

    def figures(self) -> dict[str, Any]:
        worst = self.worst()
        out: dict[str, Any] = {
            "error_frames": self.error_frames,
            "worst_state": worst[0] if worst else None,
            "worst_time": worst[1] if worst else None,
            "worst_channel": worst[2] if worst else None,
            "classes": dict(sorted(self.classes().items())),
            "channels": {name: bus.figures() for name, bus in sorted(self.channels.items())},
        }
        if self.untracked:
            out["untracked"] = self.untracked
        return out

    @classmethod
    def from_figures(cls, data: dict[str, Any]) -> BusFigures:
        return cls(
            channels={
                str(name): ChannelBus.from_figures(dict(bus))
                for name, bus in dict(data.get("channels") or {}).items()
            },
            untracked=int(data.get("untracked", 0)),
        )


@dataclass(frozen=True)
class BusStatus:
    """The bus in a status line's words: ``CAN bus-off``, ``worst bus-off 10:00:08.000Z``
    (empty while no channel left error-active), ``46 error frames: bus-error 40, ...``;
    ``state`` and ``worst_state`` name the states (for the monitor's colours)."""

    state: str
    now: str
    worst_state: str
    worst: str
    errors: str

    def words(self) -> list[str]:
        return [self.now, *([self.worst] if self.worst else []), self.errors]


def status_words(bus: BusFigures, zone: TimeZone = UTC) -> BusStatus | None:
    """What the monitor's status bar and ``record``'s status line say of the bus (None
    before the first error frame); the worst state's time in ``zone``."""
    if not bus.channels:
        return None
    now = max((b.state for b in bus.channels.values()), key=_level)
    worst = bus.worst()
    worst_state, worst_words = ERROR_ACTIVE, ""
    if worst is not None and _level(worst[0]) and worst[1] is not None:
        worst_state, worst_words = worst[0], f"worst {worst[0]} {zone.format_clock(worst[1])}"
    classes = ", ".join(f"{name} {n:,}" for name, n in bus.classes().most_common(2))
    count = bus.error_frames
    errors = f"{count:,} error frame{'' if count == 1 else 's'}"
    return BusStatus(now, f"CAN {now}", worst_state, worst_words, f"{errors}: {classes}")
