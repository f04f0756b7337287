"""The --summary of a decode, and the wording of the run's figures that ``info`` shares."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from analyzer.bus_hints import bus_hints
from analyzer.feedback_track import (
    EXPECTED_FEEDBACK_HZ,
    FEEDBACK_TOLERANCE,
    GAP_PERIODS,
    MAX_FEEDBACK_SOURCES,
    FeedbackTrack,
)
from analyzer.protocol.lru import MAX_SOURCES
from analyzer.protocol.types import Event
from analyzer.tally import Tally
from analyzer.terminal_text import printable
from analyzer.timefmt import UTC, TimeZone

Style = Callable[[str], str]


def _plain(text: str) -> str:
    return text


def _bold(text: str) -> str:
    return f"\033[1m{text}\033[0m"


def _alarm(text: str) -> str:
    return f"\033[1;31m{text}\033[0m"


def feedback_lines(tally: Tally, alarm: Style = _plain, zone: TimeZone = UTC) -> list[str]:
    """Feedback rate and longest gap per stream, as ``decode --summary`` and ``info`` say it
    (the gap's ends in ``zone``)."""
    lines: list[str] = []
    if not tally.feedback:
        return ["  feedback       " + alarm("none (the gimbal should answer at about 2 Hz)")]
    for key, track in sorted(tally.feedback.items()):
        name = "feedback" if len(tally.feedback) == 1 else f"feedback {printable(key)}"
        lines.append(f"  {name} (attitude and ranging)")
        lines.append(f"    {track.count:,} messages, {_rate(track, alarm)}")
        if track.count > 1:
            gap = (
                f"longest gap {track.longest_gap:.3f} s, "
                f"{zone.format_datetime(track.gap_start or 0.0)} .. "
                f"{zone.format_datetime(track.gap_end or 0.0)}; "
                + gap_words(track.gaps_over_threshold, track.lost_messages)
            )
            if track.gaps_over_threshold:
                gap = alarm(gap)
            lines.append(f"    {gap}")
    if tally.feedback_untracked:
        lines.append(
            f"    {tally.feedback_untracked:,} more feedback messages from streams beyond the "
            f"first {MAX_FEEDBACK_SOURCES:,} (counted; rate and gaps not timed)"
        )
    return lines


def gap_words(gaps: int, lost: int) -> str:
    """'no gap' or '2 gaps, 3 messages lost', as every command says it."""
    if not gaps:
        return "no gap (no message lost)"
    return (
        f"{gaps} gap{'s' if gaps > 1 else ''}, {lost} message{'s' if lost > 1 else ''} lost "
        f"(a silence of {GAP_PERIODS:g} feedback periods or more)"
    )


def _rate(track: FeedbackTrack, alarm: Style) -> str:
    rate = track.rate_hz
    if rate is None:
        return "rate unknown"
    text = f"{rate:.2f} Hz (expected about {EXPECTED_FEEDBACK_HZ:g} Hz)"
    if abs(rate - EXPECTED_FEEDBACK_HZ) > FEEDBACK_TOLERANCE * EXPECTED_FEEDBACK_HZ:
        text = alarm(text + " OFF")
    return text


def _count(n: int, word: str) -> str:
    return f"{n:,} {word}" + ("" if n == 1 else "s")


def bus_lines(tally: Tally, alarm: Style = _plain, zone: TimeZone = UTC) -> list[str]:
    """The CAN buses' error frames: worst state and when (in ``zone``), counts by class,
    and hints."""
    bus = tally.bus
    if not bus:
        return []
    lines = [f"  {'CAN bus':<15}{_count(bus.error_frames, 'error frame')}"]
    for name, channel in sorted(bus.channels.items()):
        worst = channel.worst
        worst_time = channel.worst_time
        when = zone.format_datetime(worst_time) if worst_time is not None else "?"
        words = f"worst {worst} at {when}"
        if worst != "error-active":
            words = alarm(words)
        counters = ""
        if channel.tx_errors_max or channel.rx_errors_max:
            counters = (
                f", error counters up to tx {channel.tx_errors_max} rx {channel.rx_errors_max}"
            )
        lines.append(
            f"    {printable(name):<11}{_count(channel.error_frames, 'error frame')}, {words}, "
            f"now {channel.state}{counters}"
        )
        by_class = ", ".join(f"{k} {v:,}" for k, v in channel.classes.most_common())
        lines.append(f"    {'':<11}{by_class}")
    if bus.untracked:
        lines.append(f"    {bus.untracked:,} more error frames of channels not followed one by one")
    for hint in bus_hints(bus, tally.frames, zone):
        lines.append(f"  {'hint':<15}{alarm(printable(hint))}")
    return lines


def crc_line(tally: Tally, alarm: Style = _plain) -> str:
    rate = tally.crc_error_rate
    if rate is None:
        return "  CRC errors     no CRC-protected messages"
    text = (
        f"{tally.crc_errors:,} of {tally.crc_checked + tally.crc_errors:,} "
        f"CRC-protected messages ({rate * 100:.2f} %)"
    )
    return "  CRC errors     " + (alarm(text) if tally.crc_errors else text)


def event_lines(tally: Tally, alarm: Style = _plain) -> list[str]:
    """Events in all, by topic, commands, diagnostics by kind."""
    lines = [
        f"  {'events':<15}{tally.events:,} ({tally.diagnostics:,} diagnostics, "
        f"{tally.with_warnings:,} with warnings)"
    ]
    if tally.topics:
        lines.append("  by topic")
        for topic, count in sorted(tally.topics.items()):
            lines.append(f"    {printable(topic):<22}{count:>9,}")
    if tally.commands:
        lines.append("  commands")
        for name, count in tally.commands.most_common():
            lines.append(f"    {printable(name):<22}{count:>9,}")
    if tally.kinds:
        lines.append("  diagnostics by kind")
        for kind, count in sorted(tally.kinds.items()):
            lines.append(f"    {alarm(f'{printable(kind):<22}')}{count:>9,}")
    return lines


class Summary:
    """The figures of a decode (a pipeline's tally) with what the reader and decoder counted."""

    def __init__(self, path: str = "", fmt: str = "", tally: Tally | None = None) -> None:
        self.path = path
        self.format = fmt
        self.tally = tally if tally is not None else Tally()
        self.input_stats: dict[str, int] = {}
        self.decoder_stats: dict[str, int] = {}
        self.time_base: str | None = None
        # Set when a file read as a raw stream was almost all damage: what it is instead.
        # The CRC figures are then no verdict on a gimbal, and the summary says so.
        self.not_a_stream: str | None = None

    def add(self, event: Event) -> None:
        """Count one event (the pipeline counts whole batches itself)."""
        self.tally.add_events((event,))

    @property
    def feedback(self) -> dict[str, FeedbackTrack]:
        return self.tally.feedback

    @property
    def crc_checked(self) -> int:
        return self.tally.crc_checked

    @property
    def crc_errors(self) -> int:
        return self.tally.crc_errors

    @property
    def crc_error_rate(self) -> float | None:
        return self.tally.crc_error_rate

    @property
    def kinds(self) -> dict[str, int]:
        return dict(self.tally.kinds)

    @property
    def commands(self) -> dict[str, int]:
        return dict(self.tally.commands)

    @property
    def span(self) -> float:
        return self.tally.span

    @property
    def first_time(self) -> float | None:
        return self.tally.first_time

    @property
    def last_time(self) -> float | None:
        return self.tally.last_time

    def finish(
        self,
        *,
        input_stats: dict[str, int] | None = None,
        decoder_stats: dict[str, int] | None = None,
        first_time: float | None = None,
        last_time: float | None = None,
        time_base: str | None = None,
    ) -> None:
        """Add the reader's and decoder's counters and the capture's own time span.

        Frames the reader skipped because their IDs are not the protocol's are other
        frames the decoder never saw: they are counted once, as ``other_frames`` of the
        decoder. ``time_base`` says how the file wrote its times (absolute, relative to
        the start, since the previous frame).
        """
        self.input_stats = dict(input_stats or {})
        self.decoder_stats = dict(decoder_stats or {})
        skipped = self.input_stats.pop("other_frames", 0)
        if skipped or "other_frames" in self.decoder_stats:
            self.decoder_stats["other_frames"] = self.decoder_stats.get("other_frames", 0) + skipped
        self.time_base = time_base
        self.tally.widen(first_time, last_time)

    def to_dict(self) -> dict[str, Any]:
        """Everything as one JSON-ready object."""
        tally = self.tally
        return {
            "summary": True,
            "path": self.path,
            "format": self.format,
            "first_time": tally.first_time,
            "last_time": tally.last_time,
            "span_s": round(tally.span, 6),
            **tally.figures(),
            "figures": tally.figures(),  # as `info --json` has them
            "time_base": self.time_base,
            "not_a_stream": self.not_a_stream,
            "input": self.input_stats,
            "decoder": self.decoder_stats,
        }

    def render(self, color: bool = False, zone: TimeZone = UTC) -> str:
        """A short readable report, its times in ``zone``."""
        bold, alarm = (_bold, _alarm) if color else (_plain, _plain)
        tally = self.tally
        # Names below come from the input (paths, recorded topics, channel names): escaped.
        title = f"Summary of {self.path}" + (f" ({self.format})" if self.format else "")
        title = printable(title)
        lines = [bold(title)]
        first, last = tally.first_time, tally.last_time
        if first is not None and last is not None and last > 0:
            span = (
                f"{zone.format_datetime(first)} .. {zone.format_datetime(last)}  "
                f"({tally.span:.3f} s)"
            )
        else:
            span = "no timestamps"
        lines.append(f"  {'time span':<15}{span}")
        if self.time_base:
            lines.append(f"  {'time base':<15}{self.time_base}")
        lines.append(f"  {'input':<15}{self._input_words()}")
        lines.extend(event_lines(tally, alarm))
        lines.extend(feedback_lines(tally, alarm, zone))
        lines.extend(bus_lines(tally, alarm, zone))
        if self.not_a_stream is None:
            lines.append(crc_line(tally, alarm))
        else:
            lines.append(f"  {'CRC errors':<15}not judged: {alarm(printable(self.not_a_stream))}")
        stream = self.decoder_stats
        if stream.get("bytes_fed"):
            lines.append(
                f"  {'framed bytes':<15}{stream['bytes_fed']:,} fed, "
                f"{stream.get('bytes_framed', 0):,} in frames, "
                f"{stream.get('bytes_discarded', 0):,} discarded, "
                f"{stream.get('bytes_pending', 0):,} pending"
            )
        return "\n".join(lines)

    def _input_words(self) -> str:
        s = self.input_stats
        d = self.decoder_stats
        parts: list[str] = []
        if "lines" in s:
            parts.append(f"{s['lines']:,} lines")
        if "packets" in s:
            port = f" {s['port']}" if "port" in s else ""
            parts.append(
                f"{s['packets']:,} packets, {s.get('tcp_packets', 0):,} TCP to/from port{port}"
            )
        frames = s.get("frames", d.get("frames", 0))
        if frames or "frames" in s:
            protocol = d.get("protocol_frames", 0)
            errors = self.tally.bus.error_frames
            other = frames - protocol - errors
            kinds = f"{protocol:,} protocol, {other:,} other" + (
                f", {_count(errors, 'error frame')}" if errors else ""
            )
            parts.append(f"{frames:,} CAN frames ({kinds})")
        if s.get("recorded_events"):
            parts.append(f"{s['recorded_events']:,} events as recorded (not decoded again)")
        if d.get("chunks"):
            parts.append(f"{d['chunks']:,} stream chunks")
        if d.get("sources_given_up"):
            parts.append(
                f"{d['sources_given_up']:,} sources' decoder state given up early "
                f"(over {MAX_SOURCES:,} at once)"
            )
        if s.get("bad_lines"):
            parts.append(f"{s['bad_lines']:,} bad lines")
        if s.get("blank_lines"):
            parts.append(f"{s['blank_lines']:,} blank lines")
        if s.get("bytes_missing"):
            parts.append(f"{s['bytes_missing']:,} TCP bytes missing")
        return ", ".join(parts) if parts else "nothing read"
