"""``read``: every event of a capture file or recording, streamed, as ``decode --json`` gives."""

from __future__ import annotations

import errno
import os
import re
from collections.abc import Generator, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TypeVar

from analyzer.errors import UsageError
from analyzer.inputs import InputReader, open_input
from analyzer.pipeline import Pipeline, default_decoder, delivered_batches
from analyzer.protocol.ids import PROTOCOL_IDS, TCP_PORT
from analyzer.protocol.types import Event

__all__ = [
    "Closable",
    "Decoding",
    "FileEvents",
    "decoded_events",
    "input_errors",
    "open_decoding",
    "read",
]

FILE_BATCH = 2048  # items handed to the pipeline at a time (1 for standard input)
Path = str | os.PathLike[str]
T = TypeVar("T")


@dataclass
class Decoding:
    """An input opened for decoding: its reader and the pipeline that decodes it (no
    sinks yet: ``decode`` adds its printer)."""

    reader: InputReader
    pipeline: Pipeline
    batch_items: int


def open_decoding(
    path: Path,
    format: str | None = None,
    *,
    port: int = TCP_PORT,
    other_frames: bool = False,
    stored: bool = False,
) -> Decoding:
    """Open ``path`` for decoding as ``decode`` and ``read`` do: only the protocol's CAN
    IDs unless ``other_frames``; ``stored`` takes a recording's events as recorded.
    UsageError for an input that cannot be read or recognised."""
    name = os.fspath(path)
    wanted = None if other_frames else PROTOCOL_IDS
    reader = open_input(name, format, port, wanted_ids=wanted, stored=stored)
    pipeline = Pipeline(decoder=default_decoder(emit_other=other_frames))
    return Decoding(reader, pipeline, 1 if name == "-" else FILE_BATCH)


def read(
    path: Path,
    format: str | None = None,
    *,
    port: int = TCP_PORT,
    other_frames: bool = False,
) -> FileEvents:
    """Every event of a capture file, in order, as it is decoded (memory does not grow
    with the file): the events ``decode --json`` prints, one ``Event`` per line.

    Reads everything ``decode`` reads: candump logs, python-can logs (.asc .blf .trc
    .csv .mf4), pcap / pcapng of the IDU's TCP link or of a CAN bus, raw TCP / UART
    dumps, ArduPilot DataFlash logs, SavvyCAN CSV, this tool's MCAP recordings (their
    raw frames decoded again) and ROS bags. The format comes from the name or the
    content; ``format`` (a ``decode --format`` value) overrides it. ``port``: the IDU's
    TCP port in pcap files; ``other_frames``: also the frames of other devices
    (``decode --raw``). A missing file raises ``FileNotFoundError``; one that cannot be
    read or recognised, ``ValueError``. Damage inside a file is no error: it comes as
    ``/diagnostics`` events. The iterator knows its file (``path``): ``analyze`` of it
    judges a recording's camera commands from its video, as ``analyze`` of the path does.

    >>> from analyzer import read
    >>> for event in read("samples/flight-candump.log"):
    ...     if event.topic == "/gimbal/command":
    ...         print(event.time, event.fields["name"], event.fields["pan_speed_dps"])
    ...         break
    1715680802.004 gimbal_control -5.0
    >>> from collections import Counter
    >>> Counter(e.topic for e in read("samples/idu-tcp.pcap"))  # doctest: +NORMALIZE_WHITESPACE
    Counter({'/gimbal/command': 44, '/gimbal/attitude': 30, '/uav/gps': 20, '/uav/altitude': 20,
             '/gimbal/ranging': 10})
    """
    with input_errors(path):
        decoding = open_decoding(path, format, port=port, other_frames=other_frames)
    return FileEvents(path, decoded_events(decoding, path))


class Closable(Iterator[T]):
    """An iterator over a generator that reads an input: ``close`` stops early, and the
    input is closed."""

    def __init__(self, items: Generator[T, None, None]) -> None:
        self._items = items

    def __next__(self) -> T:
        return next(self._items)

    def close(self) -> None:
        """Stop early: the input is closed."""
        self._items.close()


class FileEvents(Closable[Event]):
    """The events of a file as ``read`` gives them, one at a time; ``path`` is the file
    (a recording's video stays there, for ``analyze`` to judge camera commands by)."""

    def __init__(self, path: Path, events: Generator[Event, None, None]) -> None:
        super().__init__(events)
        self.path = path


def decoded_events(decoding: Decoding, path: Path) -> Generator[Event, None, None]:
    """The events of an opened input as they are decoded; the reader is closed at the end
    (or when the caller stops early)."""
    reader, pipeline = decoding.reader, decoding.pipeline
    try:
        with input_errors(path):
            for batch in delivered_batches(reader, pipeline, batch_items=decoding.batch_items):
                yield from batch.materialize()
    finally:
        reader.close()


@contextmanager
def input_errors(path: Path) -> Iterator[None]:
    """The command line's one-line input errors as a library raises them: a missing
    file as ``FileNotFoundError``, any other input that cannot be read as ``ValueError``
    (with the same message)."""
    try:
        yield
    except UsageError as exc:
        name = os.fspath(path)
        if name != "-" and "://" not in name and not os.path.lexists(name):
            raise FileNotFoundError(errno.ENOENT, "no such file", name) from None
        raise ValueError(library_words(str(exc))) from None


# The command line's options as the library's arguments, in the words of its errors.
_AS_ARGUMENTS = (
    (re.compile(r"--format (\w+)"), r'format="\1"'),
    (re.compile(r"--format\b"), "format="),
    (re.compile(r"--port\b"), "port="),
    (re.compile(r"--raw\b"), "other_frames=True"),
)


def library_words(message: str) -> str:
    """An input error as the library says it: ``format="pcap"``, not ``--format pcap``."""
    for option, argument in _AS_ARGUMENTS:
        message = option.sub(argument, message)
    return message
