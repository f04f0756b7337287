"""`gimbal-analyzer info`: what is in an MCAP recording, fast even on large files."""

from __future__ import annotations

import argparse
import json
from typing import TYPE_CHECKING

from analyzer.summary import bus_lines, crc_line, event_lines, feedback_lines
from analyzer.terminal_text import printable
from analyzer.timefmt import UTC, TimeZone

if TYPE_CHECKING:
    from analyzer.mcapio.read.info import RecordingInfo

HELP = "summarise an MCAP recording: duration, counts and rates per topic, diagnostics, gaps"
DESCRIPTION = """\
Show what an MCAP recording holds: time range and duration, messages and rate
per topic, and the figures `decode --summary` gives for the same input: events,
diagnostics by kind, the gimbal's feedback rate and longest gap (it answers
every 500 ms, so gaps over 1 s mean lost messages) and the CRC error rate.
Times are UTC (Z); --local-time shows local time with its offset.

A finished recording is summarised from its MCAP summary (checked against its
CRC) and the stats record written at the end; the data section is checked
against its CRC in one pass, and where that fails every chunk is checked and
each damaged one is listed. A live recording carries a provisional summary
after every flush: if its recorder was killed, `info` says NOT CLOSED and
counts its messages again. One cut in the middle of a write has no summary
(and one whose summary fails its CRC check is not believed): its readable part
is scanned and `info` says that the file was recovered. A ROS 2 bag (rosbag2's
MCAP storage) is read the same way; its figures come from decoding the frames of
its can_msgs/msg/Frame topics.

  gimbal-analyzer info flight.mcap
  gimbal-analyzer info flight.mcap --json
  gimbal-analyzer info flight.mcap --scan     recount diagnostics and gaps from the messages
"""

MAX_DAMAGE_LINES = 20


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("recording", help="MCAP file")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument(
        "--scan",
        action="store_true",
        help="count the recorded frames and events again even when the stats record exists",
    )


def _size(n: int) -> str:
    value = float(n)
    for unit in ("B", "kB", "MB", "GB"):
        if value < 1000 or unit == "GB":
            return f"{value:.0f} {unit}" if unit == "B" else f"{value:.1f} {unit}"
        value /= 1000
    return f"{n} B"


def _repaired_name(path: str) -> str:
    stem = path[:-5] if path.endswith(".mcap") else path
    return f"{stem}-repaired.mcap"


# Metadata keys `demo` writes about the simulator that made the recording.
SIMULATOR_KEYS = (
    ("simulator_options", "simulator"),
    ("simulator_faults", "  faults"),
    ("simulator_gimbal", "  gimbal"),
    ("simulator_heading", "  heading"),
)


def _simulator_lines(meta: dict[str, str]) -> list[str]:
    return [f"{label:<12}{meta[key]}" for key, label in SIMULATOR_KEYS if meta.get(key)]


def render(info: RecordingInfo, zone: TimeZone = UTC) -> str:
    """Human-readable report, its times in ``zone``."""
    lines = [f"file        {info.path} ({_size(info.size_bytes)}, {_state(info)})"]
    lines += _damage_lines(info)
    lines += _origin_lines(info)
    lines += _time_lines(info, zone)
    if info.topics:
        width = max(len(t.topic) for t in info.topics)
        lines.append("")
        lines.append(f"  {'topic':<{width}}  {'count':>9}  {'rate/s':>9}  schema")
        for t in info.topics:
            rate = "-" if t.rate_hz is None else f"{t.rate_hz:.2f}"
            lines.append(f"  {t.topic:<{width}}  {t.count:>9}  {rate:>9}  {t.schema}")
    lines.append("")
    lines.append(f"figures of the run, from {info.stats_from}:")
    lines.extend(event_lines(info.tally))
    lines.extend(feedback_lines(info.tally, zone=zone))
    lines.extend(bus_lines(info.tally, zone=zone))
    lines.append(crc_line(info.tally))
    # Paths, metadata, topics and kinds come from the file: no raw control characters.
    return "\n".join(printable(line) for line in lines)


def _state(info: RecordingInfo) -> str:
    """Whether the recording was finished, recovered or damaged, in words."""
    if info.summary_damaged:
        return "DAMAGED (its summary failed its checks; read sequentially)"
    if info.recovered:
        return "RECOVERED (recording was not finished)"
    if info.damage:
        return f"finished, DAMAGED ({len(info.damage)} unreadable part(s))"
    if not info.closed:
        return "NOT CLOSED (the recorder stopped without closing it; complete up to its last flush)"
    return "finished"


def _damage_lines(info: RecordingInfo) -> list[str]:
    """How it was recovered, what could not be read and how to repair it."""
    lines = []
    if info.recovered:
        lines.append(f"recovery    {info.recovery_note}")
    for detail in info.damage[:MAX_DAMAGE_LINES]:
        lines.append(f"damage      {detail}")
    if len(info.damage) > MAX_DAMAGE_LINES:
        lines.append(
            f"damage      ... and {len(info.damage) - MAX_DAMAGE_LINES} more (--json lists all)"
        )
    if info.damage and not info.recovered:
        lines.append(
            "            (the counts below come from the summary and include what was lost)"
        )
    if info.damage or info.summary_damaged:
        lines.append(
            f"repair      gimbal-analyzer convert {info.path} -o {_repaired_name(info.path)}"
        )
        lines.append("            writes a clean copy of everything readable: Foxglove refuses a")
        lines.append("            file with a damaged chunk and stops at the first damaged record")
    return lines


def _origin_lines(info: RecordingInfo) -> list[str]:
    """Where the recording came from: its source, the simulator, the writer, the document."""
    meta = info.metadata
    lines = []
    if meta.get("source"):
        lines.append(f"source      {meta['source']}")
    lines.extend(_simulator_lines(meta))
    if meta.get("tool_version"):
        lines.append(f"recorded by gimbal-analyzer {meta['tool_version']}")
    elif info.writer:  # another writer's file (a ROS bag): what its header says
        lines.append(f"written by  {info.writer}")
    if meta.get("protocol_document"):
        lines.append(f"protocol    {meta['protocol_document']}")
    return lines


def _time_lines(info: RecordingInfo, zone: TimeZone) -> list[str]:
    """Its time range, duration and message count."""
    if info.start_ns is None or info.end_ns is None:
        lines = ["time range  (no messages)"]
    else:
        lines = [
            f"time range  {zone.format_datetime(info.start_ns / 1e9)} .. "
            f"{zone.format_datetime(info.end_ns / 1e9)}",
            f"duration    {info.duration_s:.3f} s",
        ]
    lines.append(f"messages    {info.message_count}, counts from {info.counts_from}")
    return lines


def run(args: argparse.Namespace) -> int:
    from analyzer.mcapio.read.info import recording_info
    from analyzer.mcapio.read.video import video_dicts, video_lines
    from analyzer.mcapio.write.video import COMPRESSED_VIDEO, VIDEO_METADATA_KEY

    info = recording_info(args.recording, scan=args.scan)
    has_video = any(t.schema == COMPRESSED_VIDEO for t in info.topics) or bool(
        info.metadata.get(VIDEO_METADATA_KEY)
    )
    if args.json:
        out = info.to_dict()
        if has_video:
            out["video_streams"] = video_dicts(args.recording)
        print(json.dumps(out, indent=2))
    else:
        print(render(info, args.time_zone))
        if has_video:
            lines = video_lines(args.recording, args.time_zone)
            print("\n".join(printable(line) for line in lines))
    return 0
