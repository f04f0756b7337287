"""Answers of the fleet's questions as aligned text, JSON lines or CSV."""

from __future__ import annotations

import csv
import json
from collections.abc import Sequence
from datetime import date, datetime, timezone
from decimal import Decimal
from typing import IO

from analyzer.fleet.queries import Answer, Value
from analyzer.terminal_text import printable
from analyzer.timefmt import UTC, TimeZone

MAX_TEXT_ROWS = 50  # per question in the text output (--json and --csv give all)


def cell(value: Value | object) -> str | int | float | bool | None:
    """A value as JSON and CSV have it: times in UTC with Z (whatever --local-time says)."""
    if isinstance(value, datetime):
        if value.tzinfo is not None:
            value = value.astimezone(timezone.utc).replace(tzinfo=None)
        return value.isoformat(timespec="microseconds").rstrip("0").rstrip(".") + "Z"
    if isinstance(value, date):
        return value.isoformat()
    if isinstance(value, Decimal):
        return float(value)
    if value is None or isinstance(value, (str, int, float, bool)):
        return value
    return str(value)


def human(value: Value | object, zone: TimeZone = UTC) -> str | int | float | bool | None:
    """A value as people read it: times by the one time rule (analyzer.timefmt), in ``zone``."""
    if isinstance(value, datetime):
        return zone.format_datetime(value.timestamp())
    return cell(value)


def _text(value: Value | object, zone: TimeZone) -> str:
    shown = human(value, zone)
    if shown is None:
        return "-"
    if isinstance(shown, float):
        return f"{shown:.6g}"
    return printable(str(shown))


def write_text(out: IO[str], answers: Sequence[Answer], zone: TimeZone = UTC) -> None:
    """The answers as aligned columns, their times in ``zone``."""
    for n, answer in enumerate(answers):
        if n:
            out.write("\n")
        out.write(f"{answer.title}\n")
        if not answer.rows:
            out.write("  (no rows)\n")
            continue
        shown = [[_text(v, zone) for v in row] for row in answer.rows[:MAX_TEXT_ROWS]]
        widths = [
            max(len(col), *(len(r[i]) for r in shown)) for i, col in enumerate(answer.columns)
        ]
        numeric = [
            all(isinstance(row[i], (int, float, Decimal)) or row[i] is None for row in answer.rows)
            for i in range(len(answer.columns))
        ]

        out.write(_line(answer.columns, widths, numeric))
        for row in shown:
            out.write(_line(row, widths, numeric))
        if len(answer.rows) > MAX_TEXT_ROWS:
            out.write(f"  ... {len(answer.rows) - MAX_TEXT_ROWS:,} more rows (--json or --csv)\n")


def _line(cells: Sequence[str], widths: list[int], numeric: list[bool]) -> str:
    parts = [
        c.rjust(w) if num else c.ljust(w) for c, w, num in zip(cells, widths, numeric, strict=True)
    ]
    return "  " + "  ".join(parts).rstrip() + "\n"


def write_json(out: IO[str], answers: Sequence[Answer], *, named: bool) -> None:
    """One JSON object per row; with ``named`` each says which question it answers."""
    for answer in answers:
        for row in answer.rows:
            obj: dict[str, object] = {"question": answer.name} if named else {}
            obj.update((c, cell(v)) for c, v in zip(answer.columns, row, strict=True))
            out.write(json.dumps(obj) + "\n")


def write_csv(out: IO[str], answer: Answer) -> None:
    """One answer as one CSV table: a header and the rows."""
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(answer.columns)
    for row in answer.rows:
        writer.writerow(["" if (v := cell(x)) is None else v for x in row])
