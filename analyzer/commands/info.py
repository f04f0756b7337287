"""`gimbal-analyzer info`: what is in an MCAP recording, fast even on large files."""

from __future__ import annotations

import argparse
import json
import time
from typing import TYPE_CHECKING

from analyzer.terminal_text import printable

if TYPE_CHECKING:
    from analyzer.mcapio.info import RecordingInfo

HELP = "summarise an MCAP recording: duration, counts and rates per topic, diagnostics, gaps"
DESCRIPTION = """\
Show what an MCAP recording holds: time range and duration, messages and rate
per topic, diagnostics by kind and the longest gap in the gimbal's attitude
feedback (sent every 500 ms, so gaps over 1 s mean lost messages).

A finished recording is summarised from its MCAP summary and the stats record
written at the end, without reading the messages. A recording whose recorder
was killed has no summary: its readable part is scanned and `info` says that
the file was recovered.

  gimbal-analyzer info flight.mcap
  gimbal-analyzer info flight.mcap --json
  gimbal-analyzer info flight.mcap --scan     recount diagnostics and gaps from the messages
"""

_EPOCH_2000 = 946_684_800.0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("recording", help="MCAP file")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument(
        "--scan",
        action="store_true",
        help="scan /diagnostics and /gimbal/attitude even when the stats record exists",
    )


def format_time(seconds: float) -> str:
    """Unix times as UTC date and time; small values (relative logs) as seconds."""
    if seconds < _EPOCH_2000:
        return f"{seconds:.3f} s"
    whole = int(seconds)
    millis = round((seconds - whole) * 1000)
    if millis == 1000:
        whole, millis = whole + 1, 0
    return time.strftime("%Y-%m-%d %H:%M:%S", time.gmtime(whole)) + f".{millis:03d} UTC"


def _size(n: int) -> str:
    value = float(n)
    for unit in ("B", "kB", "MB", "GB"):
        if value < 1000 or unit == "GB":
            return f"{value:.0f} {unit}" if unit == "B" else f"{value:.1f} {unit}"
        value /= 1000
    return f"{n} B"


def render(info: RecordingInfo) -> str:
    """Human-readable report."""
    lines = []
    state = "RECOVERED (recording was not finished)" if info.recovered else "finished"
    lines.append(f"file        {info.path} ({_size(info.size_bytes)}, {state})")
    if info.recovered:
        lines.append(f"recovery    {info.recovery_note}")
    meta = info.metadata
    if meta.get("source"):
        lines.append(f"source      {meta['source']}")
    if meta.get("tool_version"):
        lines.append(f"recorded by gimbal-analyzer {meta['tool_version']}")
    if meta.get("protocol_document"):
        lines.append(f"protocol    {meta['protocol_document']}")
    if info.start_ns is None or info.end_ns is None:
        lines.append("time range  (no messages)")
    else:
        lines.append(
            f"time range  {format_time(info.start_ns / 1e9)} .. {format_time(info.end_ns / 1e9)}"
        )
        lines.append(f"duration    {info.duration_s:.3f} s")
    lines.append(f"messages    {info.message_count}, counts from {info.counts_from}")
    if info.topics:
        width = max(len(t.topic) for t in info.topics)
        lines.append("")
        lines.append(f"  {'topic':<{width}}  {'count':>9}  {'rate/s':>9}  schema")
        for t in info.topics:
            rate = "-" if t.rate_hz is None else f"{t.rate_hz:.2f}"
            lines.append(f"  {t.topic:<{width}}  {t.count:>9}  {rate:>9}  {t.schema}")
    lines.append("")
    stats = info.stats
    lines.append(f"diagnostics by kind, from {info.stats_from}:")
    if stats.diagnostics:
        for kind, n in sorted(stats.diagnostics.items(), key=lambda kv: (-kv[1], kv[0])):
            lines.append(f"  {kind:<20} {n:>9}")
    else:
        lines.append("  none")
    if stats.attitude_count == 0:
        lines.append("feedback    no /gimbal/attitude messages")
    elif stats.attitude_count == 1 or stats.max_gap_at is None:
        lines.append("feedback    1 /gimbal/attitude message (no gap to measure)")
    else:
        lines.append(
            f"feedback    {stats.attitude_count} /gimbal/attitude messages; longest gap "
            f"{stats.max_gap_s:.3f} s after {format_time(stats.max_gap_at)}; "
            f"{stats.gaps_over_threshold} gap(s) over 1 s"
        )
    # Paths, metadata, topics and kinds come from the file: no raw control characters.
    return "\n".join(printable(line) for line in lines)


def run(args: argparse.Namespace) -> int:
    from analyzer.mcapio.info import recording_info

    info = recording_info(args.recording, scan=args.scan)
    if args.json:
        print(json.dumps(info.to_dict(), indent=2))
    else:
        print(render(info))
    return 0
