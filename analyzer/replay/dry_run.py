"""`replay --dry-run` and the plan a replay prints first: the frames and when each would go."""

from __future__ import annotations

from analyzer.check.align import command_words, commands_for, describe
from analyzer.protocol.codec import encode_command
from analyzer.protocol.ids import CONTROL_ID
from analyzer.protocol.types import hexstr
from analyzer.replay.flight import Span
from analyzer.replay.player import start_goals
from analyzer.sim.transports import LinkSpec, to_stream
from analyzer.terminal_text import printable

WHAT_WIDTH = 52


def plan_lines(span: Span, speed: float) -> list[str]:
    """What will be sent and what not, in a few lines."""
    status = f" and {span.status:,} UAV status frames" if span.status else ""
    lines = [
        f"{span.words()}: {span.commands:,} commands{status}, at {speed:g} times the "
        f"flight's speed ({(span.end - span.start) / speed:.1f} s); the gimbal's own feedback "
        f"({span.skipped_feedback:,} messages in it) is not sent"
    ]
    if span.refused:
        lines.append(
            f"refused, not sent: {len(span.refused)} frame(s) the document does not allow:"
        )
        lines += [
            printable(f"  +{f.time - span.start:8.3f} s  {f.what}: {f.refused}")
            for f in span.refused
        ]
    return lines


def framing(can_id: int, data: bytes, spec: LinkSpec | None) -> str:
    """A frame as it goes on ``spec`` (CAN: ID#data; TCP / serial: the stream's bytes);
    without a link, both."""
    can = f"{can_id:08X}#{data.hex().upper()}"
    stream = f"TCP {hexstr(to_stream(can_id, data))}"
    if spec is None:
        return f"{can}  {stream}"
    return can if spec.kind == "can" else stream.replace("TCP", spec.kind.upper(), 1)


def dry_run_lines(span: Span, speed: float, align: bool, spec: LinkSpec | None) -> list[str]:
    """Every frame the replay would send, with the second (on the bench, after the
    alignment) it would go at; nothing is sent."""
    lines: list[str] = []
    if align and span.attitude is not None:
        goals = start_goals(span.attitude)
        lines.append(
            f"first the gimbal is brought to the flight's first attitude ({describe(goals)}), "
            "unless its feedback shows it there:"
        )
        for name, params in commands_for(goals):
            data = encode_command(name, **params)
            lines.append(_line(None, command_words(name, params), framing(CONTROL_ID, data, spec)))
    elif align:
        lines.append("the flight has no attitude feedback: the gimbal is not aligned first")
    for f in span.frames:
        lines.append(_line((f.time - span.start) / speed, f.what, framing(f.can_id, f.data, spec)))
    return lines


def _line(at: float | None, what: str, frame: str) -> str:
    when = "  (align)  " if at is None else f"+{at:8.3f} s"
    shown = what if len(what) <= WHAT_WIDTH else what[: WHAT_WIDTH - 1] + "\u2026"
    return printable(f"  {when}  {shown:<{WHAT_WIDTH}} {frame}")
