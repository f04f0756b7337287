"""The fleet report: the standard answers as one offline HTML page, in the style of `report`."""

from __future__ import annotations

import json
import time
from collections.abc import Sequence
from datetime import datetime
from importlib import resources
from typing import Any

from analyzer.analysis.findings import VERDICTS
from analyzer.fleet.output import human
from analyzer.fleet.queries import Answer, Value
from analyzer.report.page import CHART_JS, CHECK_JS, CSS, _e, _plot, _rows
from analyzer.timefmt import UTC, TimeZone
from analyzer.version import __version__


def _by_name(answers: Sequence[Answer], prefix: str) -> Answer | None:
    return next((a for a in answers if a.name.startswith(prefix)), None)


def _dicts(answer: Answer | None) -> list[dict[str, Any]]:
    if answer is None:
        return []
    return [dict(zip(answer.columns, row, strict=True)) for row in answer.rows]


def plot_data(answers: Sequence[Answer], tag: str) -> dict[str, Any]:
    """What the plots draw, from the answers (grouped by the first tag)."""
    weekly = _dicts(_by_name(answers, f"link_by_week_{tag}"))
    links = _dicts(_by_name(answers, f"link_by_{tag}"))
    obedience = _dicts(_by_name(answers, f"obedience_by_{tag}"))
    weeks = sorted({str(r["week"]) for r in weekly if r["week"] is not None})
    crc_week: dict[str, dict[str, float]] = {}
    for r in weekly:
        if r["week"] is not None and r["crc_error_rate"] is not None:
            crc_week.setdefault(str(r[tag]), {})[str(r["week"])] = float(r["crc_error_rate"])
    tag_values = [str(r[tag]) for r in links]
    gaps = {"gaps over 1 s": {str(r[tag]): int(r["gaps"] or 0) for r in links}}
    commands = sorted({str(r["command"]) for r in obedience})
    verdicts: dict[str, dict[str, int]] = {v: {} for v in VERDICTS}
    response: dict[str, dict[str, float]] = {}
    for r in obedience:
        command = str(r["command"])
        for v in VERDICTS:
            verdicts[v][command] = verdicts[v].get(command, 0) + int(r[v] or 0)
        if r["median_response_s"] is not None:
            response.setdefault(str(r[tag]), {})[command] = float(r["median_response_s"])
    return {
        "weeks": weeks,
        "crc_week": crc_week,
        "tag_values": tag_values,
        "gaps": gaps,
        "commands": commands,
        "verdicts": verdicts,
        "response": response,
    }


def _caption(text: str) -> str:
    return f'<p class="small">{_e(text)}</p>'


def _table(answer: Answer, zone: TimeZone) -> str:
    if not answer.rows:
        return '<p class="empty">no rows</p>'
    numeric = frozenset(
        i
        for i in range(len(answer.columns))
        if all(isinstance(row[i], (int, float)) or row[i] is None for row in answer.rows)
    )
    rows = [["" if (v := human(x, zone)) is None else _e(v) for x in row] for row in answer.rows]
    return _rows(rows, answer.columns, numeric)


def _tags(answers: Sequence[Answer]) -> list[str]:
    """The tags the standard answers are grouped by (``fleet`` alone when there are none)."""
    prefix = "link_by_"
    return [
        a.name[len(prefix) :]
        for a in answers
        if a.name.startswith(prefix) and not a.name.startswith("link_by_week_")
    ]


def _when(value: Value | object, zone: TimeZone) -> str:
    """A time as every human output shows it (analyzer.timefmt: UTC, or --local-time)."""
    if isinstance(value, datetime):
        return zone.format_datetime(value.timestamp())
    return "-"


def render_fleet(
    dataset: str,
    answers: Sequence[Answer],
    overview: Answer,
    extra: Sequence[Answer] = (),
    zone: TimeZone = UTC,
) -> str:
    """The whole page: the standard ``answers`` and the ``overview``, then ``extra`` ones;
    its times in ``zone``."""
    tags = [t for t in _tags(answers) if t != "fleet"]
    tag = tags[0] if tags else "fleet"
    plots = plot_data(answers, tag)
    chart_js = (resources.files("analyzer.report") / "vendor" / CHART_JS).read_text("utf-8")
    check_js = (resources.files("analyzer.report") / CHECK_JS).read_text("utf-8")
    script = (resources.files("analyzer.fleet") / "fleet.js").read_text("utf-8")
    payload = json.dumps(plots, separators=(",", ":")).replace("</", "<\\/")
    flights, failed, frames, findings, first, last = (
        overview.rows[0] if overview.rows else (0, 0, None, None, None, None)
    )
    generated = zone.format_datetime(time.time())
    kv = [
        ("dataset", _e(dataset)),
        ("recordings", f"{flights:,} ({failed:,} unreadable or damaged)"),
        ("time range", f"{_e(_when(first, zone))} to {_e(_when(last, zone))}"),
        ("CAN frames", f"{frames or 0:,}"),
        ("findings", f"{findings or 0:,}"),
        ("tags", _e(", ".join(tags) or "none")),
    ]
    sections = [
        f"<h1>Fleet report: {_e(dataset)}</h1>",
        f'<p class="sub">gimbal-analyzer {_e(__version__)}, made {_e(generated)}. '
        f"Times are {'local time' if zone.local else 'UTC'}; weeks are ISO weeks in UTC. "
        f"Plots are grouped by the first tag ({_e(tag)}).</p>",
        "<h2>Overview</h2>",
        '<table class="kv">' + "".join(f"<tr><td>{k}</td><td>{v}</td></tr>" for k, v in kv),
        "</table>",
        "<h2>CRC errors and feedback gaps</h2>",
        _caption(f"CRC error rate per week (ISO weeks, UTC), by {tag}"),
        _plot("plot-crc-week", bool(plots["crc_week"]), "no timed recordings"),
        _caption(f"Feedback gaps over 1 s, by {tag}"),
        _plot("plot-gaps", bool(plots["tag_values"]), "no readable recordings"),
        "<h2>Obedience</h2>",
        _caption("Findings per command, by verdict (feedback health not included)"),
        _plot("plot-verdicts", bool(plots["commands"]), "no command with a visible effect"),
        _caption(f"Median response time per command, by {tag}"),
        _plot("plot-response", bool(plots["response"]), "no timed responses"),
    ]
    for answer in [*answers, *extra]:
        sections += [f"<h2>{_e(answer.title)}</h2>", _table(answer, zone)]
    return "\n".join(
        [
            "<!DOCTYPE html>",
            '<html lang="en"><head><meta charset="utf-8">',
            '<meta name="viewport" content="width=device-width, initial-scale=1">',
            f"<title>Fleet report: {_e(dataset)}</title>",
            f"<style>{CSS}</style>",
            "</head><body>",
            *sections,
            f'<script id="fleet-data" type="application/json">{payload}</script>',
            f"<script>{chart_js}</script>",
            f"<script>{script}</script>",
            f"<script>{check_js}</script>",
            "</body></html>",
        ]
    )
