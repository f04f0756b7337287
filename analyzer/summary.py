"""The --summary of a decode: counts per topic and diagnostic kind, feedback rate and gaps, CRCs."""

from __future__ import annotations

import time as _time
from collections import Counter
from typing import Any

from analyzer.feedback_track import FeedbackTrack
from analyzer.protocol.types import (
    CRC_MISMATCH,
    TOPIC_COMMAND,
    TOPIC_DIAGNOSTICS,
    TOPIC_GIMBAL_ATTITUDE,
    TOPIC_GIMBAL_RANGING,
    Event,
)
from analyzer.terminal_text import printable

EXPECTED_FEEDBACK_HZ = 2.0  # the gimbal answers with one message about every 500 ms
FEEDBACK_TOLERANCE = 0.25  # a rate further off than this fraction is flagged
FEEDBACK_TOPICS = frozenset({TOPIC_GIMBAL_ATTITUDE, TOPIC_GIMBAL_RANGING})
EPOCH_THRESHOLD = 1e8


class Summary:
    """Folds events into counts; ``finish`` adds what the reader and decoder counted."""

    def __init__(self, path: str = "", fmt: str = "") -> None:
        self.path = path
        self.format = fmt
        self.events = 0
        self.topics: Counter[str] = Counter()
        self.kinds: Counter[str] = Counter()
        self.commands: Counter[str] = Counter()
        self.with_warnings = 0
        self.first_time: float | None = None
        self.last_time: float | None = None
        self.feedback: dict[str, FeedbackTrack] = {}
        self.crc_checked = 0  # messages whose CRC was checked and matched
        self.crc_errors = 0
        self.input_stats: dict[str, int] = {}
        self.decoder_stats: dict[str, int] = {}

    def add(self, event: Event) -> None:
        self.events += 1
        topic = event.topic
        self.topics[topic] += 1
        t = event.time
        if self.first_time is None or t < self.first_time:
            self.first_time = t
        if self.last_time is None or t > self.last_time:
            self.last_time = t
        if event.warnings:
            self.with_warnings += 1
        fields = event.fields
        if topic == TOPIC_DIAGNOSTICS:
            kind = str(fields.get("kind", "unknown"))
            self.kinds[kind] += 1
            if kind == CRC_MISMATCH:
                self.crc_errors += 1
            return
        if topic == TOPIC_COMMAND:
            self.commands[str(fields.get("name", "unknown"))] += 1
        if topic in FEEDBACK_TOPICS:
            key = event.source
            direction = fields.get("direction")
            if direction:
                key = f"{key} {direction}"
            track = self.feedback.get(key)
            if track is None:
                track = self.feedback[key] = FeedbackTrack()
            track.add(t)
            self.crc_checked += 1
        elif fields.get("transport") == "stream" and fields.get("crc_set", True):
            self.crc_checked += 1

    def finish(
        self,
        *,
        input_stats: dict[str, int] | None = None,
        decoder_stats: dict[str, int] | None = None,
        first_time: float | None = None,
        last_time: float | None = None,
    ) -> None:
        """Add the reader's and decoder's counters and the capture's own time span."""
        self.input_stats = dict(input_stats or {})
        self.decoder_stats = dict(decoder_stats or {})
        if first_time is not None and (self.first_time is None or first_time < self.first_time):
            self.first_time = first_time
        if last_time is not None and (self.last_time is None or last_time > self.last_time):
            self.last_time = last_time

    # -- results ---------------------------------------------------------------------------

    @property
    def span(self) -> float:
        if self.first_time is None or self.last_time is None:
            return 0.0
        return self.last_time - self.first_time

    @property
    def crc_error_rate(self) -> float | None:
        total = self.crc_checked + self.crc_errors
        return self.crc_errors / total if total else None

    def to_dict(self) -> dict[str, Any]:
        """Everything as one JSON-ready object."""
        return {
            "summary": True,
            "path": self.path,
            "format": self.format,
            "first_time": self.first_time,
            "last_time": self.last_time,
            "span_s": round(self.span, 6),
            "events": self.events,
            "events_with_warnings": self.with_warnings,
            "topics": dict(sorted(self.topics.items())),
            "diagnostics": dict(sorted(self.kinds.items())),
            "commands": dict(sorted(self.commands.items())),
            "feedback": {
                key: {
                    "messages": track.count,
                    "rate_hz": _round(track.rate_hz),
                    "expected_hz": EXPECTED_FEEDBACK_HZ,
                    "longest_gap_s": round(track.longest_gap, 6),
                    "longest_gap_end": track.gap_end if track.count > 1 else None,
                }
                for key, track in sorted(self.feedback.items())
            },
            "crc_checked": self.crc_checked,
            "crc_errors": self.crc_errors,
            "crc_error_rate": _round(self.crc_error_rate),
            "input": self.input_stats,
            "decoder": self.decoder_stats,
        }

    def render(self, color: bool = False) -> str:
        """A short readable report."""
        bold = (lambda s: f"\033[1m{s}\033[0m") if color else (lambda s: s)
        alarm = (lambda s: f"\033[1;31m{s}\033[0m") if color else (lambda s: s)
        # Names below come from the input (paths, recorded topics, channel names): escaped.
        title = f"Summary of {self.path}" + (f" ({self.format})" if self.format else "")
        title = printable(title)
        lines = [bold(title)]

        def row(name: str, text: str) -> None:
            lines.append(f"  {name:<15}{text}")

        if self.first_time is not None and self.last_time is not None and self.last_time > 0:
            row(
                "time span",
                f"{_when(self.first_time, True)} .. {_when(self.last_time, True)}"
                f"  ({self.span:.3f} s)",
            )
        else:
            row("time span", "no timestamps")
        row("input", self._input_words())
        diagnostics = self.topics.get(TOPIC_DIAGNOSTICS, 0)
        row(
            "events",
            f"{self.events:,} ({diagnostics:,} diagnostics, {self.with_warnings:,} with warnings)",
        )
        if self.topics:
            lines.append("  by topic")
            for topic, count in sorted(self.topics.items()):
                lines.append(f"    {printable(topic):<22}{count:>9,}")
        if self.commands:
            lines.append("  commands")
            for name, count in self.commands.most_common():
                lines.append(f"    {printable(name):<22}{count:>9,}")
        if self.kinds:
            lines.append("  diagnostics by kind")
            for kind, count in sorted(self.kinds.items()):
                lines.append(f"    {alarm(f'{printable(kind):<22}')}{count:>9,}")
        if not self.feedback:
            row("feedback", alarm("none (the gimbal should answer at about 2 Hz)"))
        for key, track in sorted(self.feedback.items()):
            name = "feedback" if len(self.feedback) == 1 else f"feedback {printable(key)}"
            lines.append(f"  {name}")
            rate = track.rate_hz
            if rate is None:
                rate_text = "rate unknown"
            else:
                rate_text = f"{rate:.2f} Hz (expected about {EXPECTED_FEEDBACK_HZ:g} Hz)"
                if abs(rate - EXPECTED_FEEDBACK_HZ) > FEEDBACK_TOLERANCE * EXPECTED_FEEDBACK_HZ:
                    rate_text = alarm(rate_text + " OFF")
            lines.append(f"    {track.count:,} messages, {rate_text}")
            if track.count > 1:
                ended = _when(track.gap_end or 0.0)
                gap = f"longest gap {track.longest_gap:.3f} s, ended {ended}"
                expected_gap = 1.0 / EXPECTED_FEEDBACK_HZ
                if track.longest_gap > 2 * expected_gap:
                    gap = alarm(gap)
                lines.append(f"    {gap}")
        rate = self.crc_error_rate
        if rate is None:
            row("CRC errors", "no CRC-protected messages")
        else:
            text = (
                f"{self.crc_errors:,} of {self.crc_checked + self.crc_errors:,} "
                f"CRC-protected messages ({rate * 100:.2f} %)"
            )
            row("CRC errors", alarm(text) if self.crc_errors else text)
        stream = self.decoder_stats
        if stream.get("bytes_fed"):
            row(
                "framed bytes",
                f"{stream['bytes_fed']:,} fed, {stream.get('bytes_framed', 0):,} in frames, "
                f"{stream.get('bytes_discarded', 0):,} discarded, "
                f"{stream.get('bytes_pending', 0):,} pending",
            )
        return "\n".join(lines)

    def _input_words(self) -> str:
        s = self.input_stats
        d = self.decoder_stats
        parts: list[str] = []
        if "lines" in s:
            parts.append(f"{s['lines']:,} lines")
        if "packets" in s:
            parts.append(f"{s['packets']:,} packets, {s.get('tcp_packets', 0):,} TCP to/from port")
        frames = s.get("frames", d.get("frames", 0))
        if frames or "frames" in s:
            protocol = d.get("protocol_frames", 0)
            other = frames - protocol
            parts.append(f"{frames:,} CAN frames ({protocol:,} protocol, {other:,} other)")
        if s.get("recorded_events"):
            parts.append(f"{s['recorded_events']:,} events as recorded (not decoded again)")
        if d.get("chunks"):
            parts.append(f"{d['chunks']:,} stream chunks")
        if s.get("bad_lines"):
            parts.append(f"{s['bad_lines']:,} bad lines")
        if s.get("blank_lines"):
            parts.append(f"{s['blank_lines']:,} blank lines")
        if s.get("bytes_missing"):
            parts.append(f"{s['bytes_missing']:,} TCP bytes missing")
        return ", ".join(parts) if parts else "nothing read"


def _round(value: float | None) -> float | None:
    return None if value is None else round(value, 6)


def _when(t: float, with_date: bool = False) -> str:
    if t < EPOCH_THRESHOLD:
        return f"{t:.3f} s"
    whole = int(t)
    millis = min(round((t - whole) * 1000), 999)
    layout = "%Y-%m-%d %H:%M:%S" if with_date else "%H:%M:%S"
    return _time.strftime(layout, _time.localtime(whole)) + f".{millis:03d}"
