"""How ``analyze`` writes its findings: JSON lines or the text report, in time order, as made."""

from __future__ import annotations

import json
import shutil
import tempfile
from collections.abc import Callable
from typing import IO, Any

from analyzer.analysis.verdict_counts import VerdictCounts
from analyzer.api.analysis import FindingsInOrder, Judging
from analyzer.pipeline import Batch
from analyzer.protocol.response_fields import verdict_word
from analyzer.protocol.types import Event
from analyzer.tally import Tally
from analyzer.terminal_text import printable_lines
from analyzer.timefmt import UTC, TimeZone, is_absolute

_NUMBER_FIELDS: tuple[tuple[str, str, Callable[[Any], str]], ...] = (
    ("target_deg", "target", lambda v: f"{v:g} deg"),
    ("start_deg", "start", lambda v: f"{v:.2f} deg"),
    ("final_deg", "final", lambda v: f"{v:.2f} deg"),
    ("response_s", "response", lambda v: f"{v:.2f} s"),
    ("error_deg", "error", lambda v: f"{v:.2f} deg"),
    ("pan_ratio", "pan ratio", lambda v: f"{v:.2f}"),
    ("tilt_ratio", "tilt ratio", lambda v: f"{v:.2f}"),
    ("lag_s", "lag", lambda v: f"{v:.2f} s"),
    ("command_count", "commands", lambda v: f"{v:,}" if v > 1 else ""),
    ("interval_mean_s", "every", lambda v: f"{v:.3f} s"),
    ("updates_hz", "updates", lambda v: f"{v:.1f}/s"),
)


class FindingsOutput:
    """The sink of ``analyze``: each finding written in time order once no earlier one can
    come (``FindingsInOrder``, which the Python API's ``analyze`` runs too).

    ``stage`` is the analysis as the pipeline's stage: the findings it makes, and no
    finding the input may already hold, are written. An input without a clock (see
    ``untimed``) gets no findings. The text report's lines go to a temporary file first
    (``finish`` writes the header, which needs the whole input's figures, then them);
    its times are in ``zone`` (the JSON lines keep Unix seconds).
    """

    keeps_items = False

    def __init__(
        self,
        analysis: Judging,
        tally: Tally,
        *,
        json_lines: bool,
        problems: bool,
        zone: TimeZone = UTC,
    ):
        self.json_lines = json_lines
        self.zone = zone
        self.problems = problems
        self.spool: IO[str] | None = (
            # closed by finish (the text report), or with the process
            None if json_lines else tempfile.TemporaryFile("w+", encoding="utf-8")  # noqa: SIM115
        )
        self.out: IO[str] | None = None
        self.written = 0
        self.first_time: float | None = None  # of the first finding shown
        self.counts = VerdictCounts()  # commands' verdicts apart from the feedback's health
        self.stage = FindingsInOrder(analysis, tally)

    @property
    def untimed(self) -> bool:
        """The input had no clock: its findings were not written."""
        return self.stage.untimed

    def to(self, out: IO[str]) -> FindingsOutput:
        self.out = out
        return self

    def handle(self, batch: Batch) -> None:
        """After the counters took the batch: write what no finding to come can precede."""
        self._show(self.stage.ready())

    def close(self) -> None:
        self._show(self.stage.rest())

    def _show(self, findings: list[Event]) -> None:
        """Findings in their turn: counted, and written unless --problems leaves them out."""
        lines: list[str] = []
        for event in findings:
            self.counts.add(event.fields)
            if self.problems and event.fields.get("verdict") == "obeyed":
                continue
            if self.first_time is None or event.time < self.first_time:
                self.first_time = event.time
            lines.append(self._line(event))
        self._write(lines)

    def finish(self, header: str) -> None:
        """The text report: header, the findings written so far, the verdict counts and
        the feedback's health."""
        out, spool = self.out, self.spool
        assert out is not None and spool is not None
        out.write(printable_lines(header) + "\n")
        if self.first_time is not None and is_absolute(self.first_time):
            day = self.zone.format_datetime(self.first_time)[:10]
            out.write(f"times are {'local' if self.zone.local else 'UTC'}, {day}\n")
        out.write("\n")
        spool.seek(0)
        shutil.copyfileobj(spool, out)
        spool.close()
        if not self.written:
            out.write("no findings\n")
        out.write(f"\nverdicts: {self.counts.verdict_line()}\n")
        out.write(f"feedback: {self.counts.health_line()}\n")

    def _line(self, event: Event) -> str:
        if self.json_lines:
            return json.dumps(event.to_dict())
        return printable_lines(finding_line(event, self.zone))  # names may come from the input

    def _write(self, lines: list[str]) -> None:
        target = self.spool if self.spool is not None else self.out
        if lines and target is not None:
            self.written += len(lines)
            target.write("\n".join(lines) + "\n")


def clock(t: float, zone: TimeZone = UTC) -> str:
    """Time of day with milliseconds, UTC with a Z (or local time with its offset after
    --local-time: ``zone``); seconds from the start for relative times."""
    if not is_absolute(t):
        return f"{t:10.3f} s"
    return zone.format_clock(t)


def finding_line(event: Event, zone: TimeZone = UTC) -> str:
    """One finding of the text report: time, command, check, verdict, detail, numbers."""
    f = event.fields
    numbers = _numbers(f)
    return (
        f"{clock(event.time, zone)}  {f['command']:<16} {f['check']:<12} "
        f"{verdict_word(f):<10}  {f['detail']}" + (f"  [{numbers}]" if numbers else "")
    )


def _numbers(fields: dict[str, Any]) -> str:
    shown = ((word, fmt(fields[key])) for key, word, fmt in _NUMBER_FIELDS if key in fields)
    return ", ".join(f"{word} {text}" for word, text in shown if text)
