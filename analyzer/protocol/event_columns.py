"""The events of a block of frames, kept as columns until someone needs them one by one.

The columnar decoder (``vector_decode``) gives, for each layout it decoded in vectors
(a command, a status frame, a feedback message, other devices' frames), an
``EventGroup``: the rows it came from, times, sources and each field's values as lists.
Everything decoded one at a time (frames and messages with a warning, text,
diagnostics) is a list of ready ``Event`` objects with their rows. ``EventColumns``
keeps both: ``events()`` makes the Events in frame order (what every sink would have
got), ``json_lines()`` writes what ``decode --json`` prints for each of them without
making them, and the counters take the groups as counts.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable, Collection, Iterable, Mapping
from dataclasses import dataclass, field
from itertools import pairwise, repeat
from operator import itemgetter
from typing import Any

from analyzer.protocol.types import Event

_ROW = itemgetter(0)

# Where blocks' events stand among a batch's other events: (the index in the batch's
# event list before which they come, the block's events).
ColumnSlots = list[tuple[int, "EventColumns"]]


@dataclass(slots=True)
class EventGroup:
    """Events of one layout, one per row, none with a warning.

    ``rows`` and ``times`` are arrays; ``values()`` gives each field's values (lists, by
    key), made by ``make`` when first wanted (the events one by one, their JSON, a
    table's columns); ``constants`` are the keys whose value is the same in every
    event."""

    topic: str
    rows: Any
    times: Any
    sources: list[str]
    keys: tuple[str, ...]
    constants: dict[str, Any]
    make: Callable[[], dict[str, list[Any]]]
    name: str | None = None  # the command's name (commands only)
    _values: dict[str, list[Any]] | None = field(default=None, repr=False)

    def values(self) -> dict[str, list[Any]]:
        if self._values is None:
            self._values = self.make()
        return self._values

    def __len__(self) -> int:
        return int(self.rows.shape[0])

    def events(self) -> list[Event]:
        topic = self.topic
        return [
            Event(topic, time, source, fields, [])
            for time, source, fields in zip(
                self.times.tolist(), self.sources, self.fields(), strict=True
            )
        ]

    def fields(self, only: Collection[str] | None = None) -> list[dict[str, Any]]:
        """Each event's fields, as its Event holds them (``only``: just those keys)."""
        keys = self.keys if only is None else tuple(k for k in self.keys if k in only)
        constants, values = self.constants, self.values()
        columns = [repeat(constants[k]) if k in constants else values[k] for k in keys]
        return list(map(dict, map(zip, repeat(keys), zip(*columns, strict=False))))

    def json_lines(self) -> list[str]:
        """What ``json.dumps(event.to_dict(), default=str)`` gives for each event."""
        # The constant text between the values: each line is the parts and the values,
        # one after the other.
        parts = [f'{{"topic": {_dumps(self.topic)}, "time": ', ', "source": ', ', "warnings": []']
        sources = self.sources
        unique = set(sources)
        if len(unique) == 1:
            text = _dumps(sources[0])
            source_column = [text] * len(sources)
        else:
            names = {s: _dumps(s) for s in unique}
            source_column = [names[s] for s in sources]
        columns: list[list[str]] = [list(map(float.__repr__, self.times.tolist())), source_column]
        values = self.values()
        for key in self.keys:
            item = f", {_dumps(key)}: "
            if key in self.constants:
                parts[-1] += item + _dumps(self.constants[key])
                continue
            parts[-1] += item
            parts.append("")
            columns.append(_json_column(values[key]))
        parts[-1] += "}"
        texts: list[Iterable[str]] = [repeat(parts[0])]
        for column, part in zip(columns, parts[1:], strict=True):
            texts += [column, repeat(part)]
        return list(map("".join, zip(*texts, strict=False)))  # the parts repeat for ever


def _json_column(values: list[Any]) -> list[str]:
    if not values:
        return []
    first = values[0]
    if isinstance(first, bool):
        return ["true" if v else "false" for v in values]
    if isinstance(first, int):
        return list(map(int.__repr__, values))
    if isinstance(first, float):  # finite: json writes float.__repr__
        return list(map(float.__repr__, values))
    if isinstance(first, str):
        try:
            escaped = _ESCAPED.search("".join(values)) is not None
        except TypeError:  # not text only
            escaped = True
        if not escaped:
            return [f'"{v}"' for v in values]  # what json writes for text it need not escape
    known: dict[Any, str] = {}
    return [known[v] if v in known else known.setdefault(v, _dumps(v)) for v in values]


# What ``json.dumps`` escapes in a string: control characters, quotes, backslashes and,
# as it ensures ASCII, anything beyond.
_ESCAPED = re.compile(r"[^ !#-\[\]-~]")


def _dumps(value: Any) -> str:
    return json.dumps(value, default=str)


@dataclass(slots=True)
class EventColumns:
    """The events of one block of frames: groups decoded in vectors and single events,
    each at the row of the frame that gave it."""

    groups: list[EventGroup] = field(default_factory=list)
    single_rows: list[int] = field(default_factory=list)
    singles: list[Event] = field(default_factory=list)

    def __len__(self) -> int:
        return sum(map(len, self.groups)) + len(self.singles)

    def add(self, row: int, events: list[Event]) -> None:
        """Events decoded one by one from the frame at ``row``."""
        if events:
            self.single_rows.extend([row] * len(events))
            self.singles.extend(events)

    def single_events(self) -> list[tuple[int, Event]]:
        """The events decoded one by one, with their rows, in frame order."""
        pairs = list(zip(self.single_rows, self.singles, strict=True))
        if any(a > b for a, b in pairwise(self.single_rows)):
            pairs.sort(key=_ROW)
        return pairs

    def _ordered(self, make: Callable[[EventGroup], list[Any]], singles: list[Any]) -> list[Any]:
        if not self.groups:
            at = self.single_rows
            if all(a <= b for a, b in pairwise(at)):
                return singles
            return [singles[i] for i in sorted(range(len(at)), key=at.__getitem__)]
        rows: list[int] = []
        items: list[Any] = []
        for group in self.groups:
            rows += group.rows.tolist()
            items += make(group)
        rows += self.single_rows
        items += singles
        import numpy as np

        order = np.argsort(np.array(rows, np.int64), kind="stable").tolist()
        return [items[i] for i in order]

    def events(self) -> list[Event]:
        """Every event, in the order of the frames that gave them."""
        return self._ordered(EventGroup.events, self.singles)

    def moments(
        self,
        events: Collection[str],
        fields: Collection[str],
        only: Mapping[str, Collection[str]] | None = None,
    ) -> list[Event | tuple[float, str, dict[str, Any] | None]]:
        """Every event in frame order: an Event when its topic is in ``events``, else its
        time, topic and fields when its topic is in ``fields``, else its time and topic
        (None for fields: nothing made of them). ``only``: the keys wanted of the
        commands it names (the others' fields are whole)."""

        def make(group: EventGroup) -> list[Any]:
            topic = group.topic
            if topic in events:
                return group.events()
            if topic in fields:
                made: Iterable[Any] = group.fields(
                    only.get(group.name) if only and group.name else None
                )
            else:
                made = repeat(None)
            return list(zip(group.times.tolist(), repeat(topic), made))

        return self._ordered(make, self.singles)

    def json_lines(self, wanted: Callable[[Event], bool] | None = None) -> list[str]:
        """The ``decode --json`` line of every event (that ``wanted`` takes), in order."""
        if wanted is not None:
            return [_dumps(e.to_dict()) for e in self.events() if wanted(e)]
        singles = [_dumps(e.to_dict()) for e in self.singles]
        return self._ordered(EventGroup.json_lines, singles)
