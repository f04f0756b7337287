"""``gimbal-analyzer decode``: a capture file as readable lines, JSON lines or a summary."""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Callable
from typing import IO, Any

from analyzer.errors import UsageError
from analyzer.progress import Progress
from analyzer.protocol.ids import PROTOCOL_IDS
from analyzer.terminal_text import printable
from analyzer.timefmt import UTC, TimeZone

HELP = "decode a capture file (candump, python-can logs, pcap, raw dumps, MCAP) into events"

DESCRIPTION = """\
Decode a capture file and print one line per decoded message or diagnostic.

The format comes from the file name (.log candump; .asc .blf .trc .csv .mf4
through python-can, .gz too; SavvyCAN .csv; .pcap/.pcapng; .bin an ArduPilot
DataFlash log or raw TCP/UART bytes, by content; .mcap recordings and ROS 2
bags; .bag ROS 1 bags; .db3 rosbag2 SQLite files: the can_msgs/Frame topics of
a bag, each topic as the frames' channel) or from its content; --format
overrides it. Damaged lines, CRC errors, lost
segments and the like are reported as /diagnostics events and decoding goes
on: the exit code is 0 whenever the file could be read.

examples:
  gimbal-analyzer decode samples/flight-candump.log
  gimbal-analyzer decode samples/idu-tcp.pcap --json
  gimbal-analyzer decode samples/uart-dump.bin --summary
  gimbal-analyzer decode 00000042.BIN           # CAN frames an ArduPilot logged
  gimbal-analyzer decode export.txt --format asc --topic /gimbal/command
  gimbal-analyzer decode flight.log --name gimbal_control --name crc_mismatch
  gimbal-analyzer decode flight.log --raw          # also frames of other devices
  candump -L can0 | gimbal-analyzer decode -       # live from a CAN interface
  gimbal-analyzer decode flight_0.mcap --summary   # ros2 bag record of /from_can_bus

--topic takes a topic (/gimbal/command), a prefix (/uav, or uav) or a last
part (attitude, diagnostics); --name a command name (gimbal_control) or a
diagnostic kind (crc_mismatch); both may be repeated. --summary counts every
event, whatever the filters.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from analyzer.input_options import add_input_arguments

    add_input_arguments(parser)
    parser.add_argument(
        "--stored",
        action="store_true",
        help="MCAP recordings: show the events as recorded instead of decoding the raw "
        "frames again with this version (the default)",
    )
    parser.add_argument("--json", action="store_true", help="one JSON object per event")
    parser.add_argument(
        "--summary",
        action="store_true",
        help="print counts per topic and diagnostic, feedback rate and gaps, CRC error rate",
    )
    parser.add_argument(
        "--topic", action="append", default=[], help="only events of this topic (repeatable)"
    )
    parser.add_argument(
        "--name",
        action="append",
        default=[],
        help="only commands of this name / diagnostics of this kind (repeatable)",
    )
    parser.add_argument(
        "--raw", action="store_true", help="also show CAN frames that are not part of the protocol"
    )
    parser.add_argument(
        "--color",
        choices=("auto", "always", "never"),
        default="auto",
        help="colour the lines (auto: when standard output is a terminal and NO_COLOR is unset)",
    )


class LinePrinter:
    """Sink writing the events of each batch that pass the filter, as lines or JSON lines."""

    keeps_items = False  # events only: frames may come as runs
    takes_columns = True  # blocks decoded in vectors are written as JSON from their columns

    def __init__(
        self,
        out: IO[str],
        render: Callable[[Any], str],
        wanted: Callable[[Any], bool] | None,
        *,
        flush_each: bool,
        as_json: bool = False,
    ) -> None:
        self.out = out
        self.render = render
        self.wanted = wanted
        self.flush_each = flush_each  # live input: every batch is shown at once
        self.as_json = as_json  # ``render`` writes ``decode --json`` lines

    def handle(self, batch: Any) -> None:
        lines: list[str] = []
        for segment in batch.segments():
            if isinstance(segment, list):
                lines += self._lines(segment)
            elif self.as_json:
                lines += segment.json_lines(self.wanted)
            else:
                lines += self._lines(segment.events())
        _write(self.out, lines, flush=self.flush_each)

    def _lines(self, events: list[Any]) -> list[str]:
        render, wanted = self.render, self.wanted
        if wanted is None:
            return [render(event) for event in events]
        return [render(event) for event in events if wanted(event)]

    def close(self) -> None:
        self.out.flush()


def run(args: argparse.Namespace) -> int:
    from analyzer.api.reading import open_decoding
    from analyzer.input_options import check_port
    from analyzer.pipeline import run_reader
    from analyzer.summary import Summary

    check_port(args.port)
    wanted = event_filter(args.topic, args.name)
    out = sys.stdout
    color = use_color(args.color, out)
    # The reader and pipeline of the Python API's read(): the same events.
    decoding = open_decoding(
        args.file, args.format, port=args.port, other_frames=args.raw, stored=args.stored
    )
    reader, pipeline = decoding.reader, decoding.pipeline
    live = args.file == "-"
    # With --summary only the summary is printed (as one JSON object with --json).
    if not args.summary:
        printer = make_printer(args.json, color, args.time_zone)
        pipeline.sinks.append(LinePrinter(out, printer, wanted, flush_each=live, as_json=args.json))
    progress = Progress.maybe(reader, sys.stderr, out, args.summary)
    # Ctrl-C ends live input: finished as at its end.
    interrupted = run_reader(
        reader, pipeline, batch_items=decoding.batch_items, progress=progress, interruptible=live
    )
    decoder_stats: dict[str, int] = getattr(pipeline.decoder, "stats", {})
    tally = pipeline.tally
    from analyzer.inputs.raw_stream import raw_stream_mismatch

    mismatch = raw_stream_mismatch(reader, decoder_stats, tally.crc_checked, tally.crc_errors)
    if args.summary:
        summary = Summary(args.file, reader.format_name, tally)
        summary.not_a_stream = mismatch[0] if mismatch else None
        summary.finish(
            input_stats=reader.stats,
            decoder_stats=decoder_stats,
            first_time=pipeline.clock.bounded(reader.first_time),
            last_time=reader.last_time,
            time_base=reader.time_base,
        )
        if args.json:
            out.write(json.dumps(summary.to_dict(), default=str) + "\n")
        else:
            out.write(summary.render(color, args.time_zone) + "\n")
        out.flush()
    elif sys.stderr.isatty() and not live:
        sys.stderr.write(
            f"{tally.events:,} events ({tally.diagnostics:,} diagnostics) from {args.file}\n"
        )
    from analyzer.bus_hints import bus_hints

    errors = tally.bus.error_frames
    hints = [] if args.summary else bus_hints(tally.bus, tally.frames, args.time_zone)
    nothing = _nothing_for_us(reader.stats, decoder_stats, args.raw, errors)
    for note in [*reader.notes, *nothing, *hints, *mismatch]:
        sys.stderr.write(f"note: {printable(note)}\n")
    return 130 if interrupted else 0


def _nothing_for_us(
    input_stats: dict[str, int],
    decoder_stats: dict[str, int],
    raw: bool = False,
    error_frames: int = 0,
) -> list[str]:
    """A note when CAN data frames were read but none of them belongs to the protocol.

    Error frames are no answer to "is this the gimbal's bus?": the bus hints speak of them.
    """
    frames = input_stats.get("frames", decoder_stats.get("frames", 0)) - error_frames
    if frames > 0 and not decoder_stats.get("protocol_frames") and not decoder_stats.get("chunks"):
        ids = ", ".join(f"0x{i:08X}" for i in sorted(PROTOCOL_IDS))
        where = "they are the /can/other events" if raw else "--raw shows them"
        return [
            f"none of the {frames:,} CAN frames uses a protocol ID ({ids}); "
            f"is this the gimbal's bus? ({where})"
        ]
    return []


def _write(out: IO[str], lines: list[str], flush: bool) -> None:
    if lines:
        out.write("\n".join(lines) + "\n")
        lines.clear()
    if flush:
        out.flush()


def use_color(choice: str, out: IO[str]) -> bool:
    """Colour when asked for, or (auto) on a terminal that shows it (a Windows console
    once its virtual-terminal mode is on) unless NO_COLOR is set."""
    from analyzer.ansi import ansi_ok

    if choice == "always":
        ansi_ok(out)  # turns a Windows console's virtual-terminal mode on
        return True
    if choice == "never":
        return False
    return not os.environ.get("NO_COLOR") and ansi_ok(out)


def make_printer(as_json: bool, color: bool, zone: TimeZone = UTC) -> Callable[[Any], str]:
    """Each event as a ``--json`` line, or as a text line with its times in ``zone``."""
    if as_json:

        def to_json(event: Any) -> str:
            return json.dumps(event.to_dict(), default=str)

        return to_json
    from analyzer.render import render_event

    return lambda event: render_event(event, color=color, zone=zone)


def event_filter(topics: list[str], names: list[str]) -> Callable[[Any], bool] | None:
    """A predicate from --topic / --name values; UsageError for values that match nothing."""
    from analyzer.protocol.codec import COMMANDS
    from analyzer.protocol.types import DIAGNOSTIC_KINDS, TOPIC_CAN_OTHER, TOPICS

    known_topics = (*TOPICS, TOPIC_CAN_OTHER)
    topic_set: set[str] = set()
    for value in _split(topics):
        matched = [t for t in known_topics if _topic_matches(t, value)]
        if not matched:
            prefixes = sorted({"/" + t.strip("/").split("/")[0] for t in known_topics})
            raise UsageError(
                f"unknown topic {value!r}; valid: a topic ({', '.join(known_topics)}), a "
                f"prefix ({', '.join(prefixes)}; or without the /: gimbal, uav) or a last "
                "part (attitude, diagnostics)"
            )
        topic_set.update(matched)
    known_names = {row.name for row in COMMANDS} | {"unknown", *DIAGNOSTIC_KINDS}
    name_set: set[str] = set()
    for value in _split(names):
        if value not in known_names:
            raise UsageError(
                f"unknown name {value!r}; valid: command names (see 'gimbal-analyzer commands') "
                f"or diagnostic kinds ({', '.join(DIAGNOSTIC_KINDS)})"
            )
        name_set.add(value)
    if not topic_set and not name_set:
        return None

    def wanted(event: Any) -> bool:
        if topic_set and event.topic not in topic_set:
            return False
        if name_set:
            fields = event.fields
            return fields.get("name") in name_set or fields.get("kind") in name_set
        return True

    return wanted


def _split(values: list[str]) -> list[str]:
    return [part.strip() for value in values for part in value.split(",") if part.strip()]


def _topic_matches(topic: str, value: str) -> bool:
    value = value.rstrip("/")
    if not value:
        return False
    if value.startswith("/"):
        return topic == value or topic.startswith(value + "/")
    # without the leading /: a prefix (gimbal, uav/gps) or a last part (attitude)
    return _topic_matches(topic, "/" + value) or topic.endswith("/" + value)
