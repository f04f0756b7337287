"""``Recording``: a recording's events as recorded, and each topic as an Arrow table."""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator
from typing import TYPE_CHECKING

from analyzer.api.reading import Path, input_errors
from analyzer.mcapio.channels import ROLE_EVENT
from analyzer.mcapio.read.reader import McapRecording as McapRecording
from analyzer.protocol.types import Event

if TYPE_CHECKING:
    import pyarrow as pa

__all__ = ["Recording"]

TABLE_EVENTS = 16_384  # events handed to the table's columns at a time


class Recording:
    """An MCAP recording of this tool (``record``, ``convert``, ``demo``) opened for reading.

    ``topics()`` lists the event topics it holds, ``events(topics)`` gives their events
    as recorded (decoded by the version that wrote the file; ``read(path)`` decodes its
    raw frames again with this one), in arrival order, and ``table(topic)`` one topic as
    a ``pyarrow.Table``. A recording whose writer was killed is read as far as it can
    be (``recovered``); a lost part comes as an ``incomplete`` diagnostic. A missing
    file raises ``FileNotFoundError``, one that is no MCAP file ``ValueError``.

    >>> import tempfile, os
    >>> from analyzer.cli import main  # gimbal-analyzer convert: a log into a recording
    >>> path = os.path.join(tempfile.mkdtemp(), "flight.mcap")
    >>> main(["convert", "samples/flight-candump.log", "-o", path, "-q"])
    0
    >>> from analyzer import Recording
    >>> recording = Recording(path)
    >>> recording.topics()  # doctest: +NORMALIZE_WHITESPACE
    ['/analysis/response', '/diagnostics', '/gimbal/attitude', '/gimbal/command',
     '/gimbal/ranging', '/uav/altitude', '/uav/attitude', '/uav/gps', '/uav/text']
    >>> [e.fields["text"] for e in recording.events("/uav/text")]
    ['ARMED, TAKEOFF AT 10:00, ALT HOLD 100 M']
    >>> commands = recording.table("/gimbal/command")
    >>> commands.num_rows, commands.column("name")[0], commands.column("pan_speed_dps")[0]
    (45, <pyarrow.StringScalar: 'gimbal_control'>, <pyarrow.DoubleScalar: -5.0>)
    """

    def __init__(self, path: Path) -> None:
        self.path = os.fspath(path)
        with input_errors(self.path):
            self._recording = McapRecording(self.path)

    @property
    def recovered(self) -> bool:
        """The file was not finished (its writer was killed): read through the recover path."""
        return self._recording.recovered

    def topics(self) -> list[str]:
        """The event topics the recording holds (``/gimbal/attitude``, ...), sorted."""
        kinds = self._recording.channel_kinds()
        if kinds is None:  # an unfinished file: its channels are known once read
            for _ in self._recording.messages(roles=set()):
                pass
            kinds = self._recording.channel_kinds() or []
        return sorted({k.topic for k in kinds if k.ours and k.role == ROLE_EVENT})

    def events(self, topics: str | Iterable[str] | None = None) -> Iterator[Event]:
        """The events as recorded, in arrival order: all, or those of ``topics`` (one
        topic or several)."""
        wanted = {topics} if isinstance(topics, str) else None if topics is None else set(topics)
        with input_errors(self.path):
            yield from self._recording.events(wanted)

    def table(self, topic: str) -> pa.Table:
        """The events of ``topic`` as a ``pyarrow.Table``: the columns of the fleet
        dataset's table of that topic (``gimbal-analyzer table``), one per field, typed
        from the topic's schema: ``recording`` (the file name), ``content_hash``,
        ``time`` (UTC timestamp), ``source``, the fields (a labelled value as its label,
        its number in the ``<name>_code`` column), ``warnings``, and ``extra`` (JSON of
        fields the schema does not name). ``ValueError`` for a topic without a table;
        ``MissingExtra`` without the fleet extra (pyarrow)."""
        from analyzer.extras import FLEET, require

        require(FLEET, "Recording.table")
        from analyzer.fleet.column_sink import CollectedTables, ColumnSink
        from analyzer.fleet.columns import TOPIC_TABLES, event_schema
        from analyzer.fleet.runner import plan
        from analyzer.pipeline import Batch

        name = TOPIC_TABLES.get(topic)
        if name is None:
            raise ValueError(f"no table for topic {topic!r}; valid: {', '.join(TOPIC_TABLES)}")
        work = plan(self.path, {})
        tables = CollectedTables()
        sink = ColumnSink(tables, work.recording, work.content_hash)
        batch: list[Event] = []
        for event in self.events(topic):
            batch.append(event)
            if len(batch) >= TABLE_EVENTS:
                sink.handle(Batch(events=batch))
                batch = []
        sink.handle(Batch(events=batch))
        sink.close()
        table = tables.tables().get(name)
        return event_schema(topic).empty_table() if table is None else table
