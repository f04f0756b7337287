"""The report as one self-contained HTML page: tables in HTML, plots drawn by inlined Chart.js."""

from __future__ import annotations

import json
import time
from importlib import resources
from typing import Any

from analyzer.protocol.types import Event
from analyzer.render import describe_event
from analyzer.report import camera, camera_judged, tables
from analyzer.report.collect import ReportData
from analyzer.report.decimate import Row
from analyzer.report.tables import _e, _rows
from analyzer.timefmt import UTC, TimeZone
from analyzer.version import __version__

MARK_LABEL = 34  # characters of a command mark's label

__all__ = ["CHART_JS", "CHECK_JS", "CSS", "_e", "_plot", "_rows", "render"]

CHART_JS = "chart.umd.min.js"  # Chart.js 4.6.1, MIT (vendor/chart.js-LICENSE.md)
CHECK_JS = "plots_check.js"  # shared with the fleet report: what the page checks can read

CSS = """
body { font: 14px/1.45 system-ui, sans-serif; margin: 0 auto; max-width: 1200px;
       padding: 0 16px 40px; color: #222; }
h1 { font-size: 22px; margin: 18px 0 4px; } h2 { font-size: 18px; margin: 28px 0 8px;
     border-bottom: 1px solid #ddd; padding-bottom: 4px; }
.sub { color: #666; margin: 0 0 12px; }
table { border-collapse: collapse; width: 100%; font-size: 13px; }
th, td { text-align: left; padding: 3px 8px; border-bottom: 1px solid #eee; vertical-align: top; }
th { background: #f5f5f5; } td.num { text-align: right; white-space: nowrap; }
table.kv td:first-child { width: 200px; color: #555; }
.plot { position: relative; height: 300px; margin: 6px 0 18px; }
.plot.square { height: 420px; max-width: 640px; }
.empty { color: #888; font-style: italic; margin: 8px 0 18px; }
.v { display: inline-block; padding: 0 6px; border-radius: 3px; color: #fff; font-size: 12px; }
.v-obeyed { background: #2ca02c; } .v-partial { background: #ff9800; }
.v-not_obeyed { background: #d62728; } .v-unknown { background: #888; }
.v-healthy { background: #2ca02c; } .v-degraded { background: #ff9800; }
.v-lost { background: #d62728; }
.small { font-size: 12px; color: #666; }
h3.group { font-size: 15px; margin: 18px 0 2px; }
.zoom-box { position: absolute; background: rgba(31,119,180,0.15); pointer-events: none; }
button#zoom-reset { font-size: 12px; margin: 0 0 6px; }
"""


def _plot(plot_id: str, has_data: bool, empty: str, square: bool = False) -> str:
    if not has_data:
        return f'<p class="empty">{_e(empty)}</p>'
    cls = "plot square" if square else "plot"
    return f'<div class="{cls}"><canvas id="{plot_id}"></canvas></div>'


def _mark_label(event: Event, zone: TimeZone) -> str:
    """A command in words, short enough to stand along a plot's height."""
    words = " ".join(describe_event(event, zone).split())
    return words if len(words) <= MARK_LABEL else words[: MARK_LABEL - 1] + "\u2026"


def _zone_words(zone: TimeZone) -> str:
    if zone.local:
        return "Times in the tables are local time (with their UTC offset); the plots' are UTC."
    return "Times are UTC."


def _plot_data(data: ReportData, zone: TimeZone) -> dict[str, Any]:
    start = data.first or 0.0

    def rel(rows: list[Row]) -> list[list[Any]]:
        return [[round(r[0] - start, 3), *(round(v, 3) for v in r[1:])] for r in rows]

    track = [[round(r[1], 1), round(r[2], 1)] for r in data.track.rows()]
    bounds = None
    if track:
        easts, norths = [p[0] for p in track], [p[1] for p in track]
        bounds = [min(easts), max(easts), min(norths), max(norths)]
    targets = [[round(r[0] - start, 3), *r[1:]] for r in data.target_rows()]
    return {
        "start": start,
        "span": round((data.last or start) - start, 3),
        "attitude": rel(data.attitude.rows()),
        "marks": [[round(r[0] - start, 3), _mark_label(r[1], zone)] for r in data.marks.rows()],
        "targets": targets,
        "commanded": rel(data.commanded_rows()),
        "measured": rel(data.measured.rows()),
        "feedback": rel(data.feedback_per_second()),
        "errors": rel(data.errors_per_second()),
        "altitude": rel(data.altitude.rows()),
        "track": track,
        "track_bounds": bounds,
    }


def _resolution(data: ReportData) -> str:
    """What the plots hold: every sample, or each time bucket's extremes."""
    series = [data.attitude, data.commanded, data.measured, data.altitude, data.track]
    if all(s.whole for s in series):
        return "The plots hold every sample."
    width = max(s.width for s in series if not s.whole)
    attitude = "The attitude plots hold every sample. " if data.attitude.whole else ""
    return (
        f"{attitude}Where a series is long, the plots hold per time bucket (here up to "
        f"{width * 1000:,.0f} ms) the samples with the lowest and the highest value, so no "
        "peak is lost; every sample is in <code>gimbal-analyzer decode FILE --json</code>."
    )


def render(
    data: ReportData,
    settings: str,
    pictures: camera.PictureChoice | None = None,
    lead: str = "",
    judged: str = "",
    zone: TimeZone = UTC,
) -> str:
    """The whole page: ``pictures`` are the camera pictures chosen for it, if any; ``lead``
    is HTML of a command's own shown first (the check's steps); ``judged`` the section of
    the camera commands judged from the video; the tables' times in ``zone``."""
    plots = _plot_data(data, zone)
    chart_js = (resources.files("analyzer.report") / "vendor" / CHART_JS).read_text("utf-8")
    script = (resources.files("analyzer.report") / "script.js").read_text("utf-8")
    check_js = (resources.files("analyzer.report") / CHECK_JS).read_text("utf-8")
    payload = json.dumps(plots, separators=(",", ":")).replace("</", "<\\/")
    timed = plots["span"] > 0  # a raw byte dump has no clock: nothing to plot over time
    has = {key: bool(plots[key]) and (timed or key == "track") for key in plots}

    def why(text: str) -> str:
        return text if timed else "the input carries no timestamps: nothing to plot over time"

    title = f"Flight report: {data.source}"
    generated = time.strftime("%Y-%m-%d %H:%M:%SZ", time.gmtime())
    notes = "".join(f'<p class="small">note: {_e(n)}</p>' for n in data.notes)
    sections = [
        f"<h1>{_e(title)}</h1>",
        f'<p class="sub">gimbal-analyzer {_e(__version__)}, made {generated}. {_zone_words(zone)} '
        "The protocol has no acknowledgements: each command is judged from the attitude "
        "feedback that followed it.</p>",
        notes,
        lead,
        "<h2>Overview</h2>",
        tables.overview(data, settings, zone),
        "<h2>Gimbal attitude</h2>",
        '<p class="small">Dashed lines: commands. Crosses: target angles, coloured by verdict. '
        "Drag across a time plot to zoom in (every time plot follows), double-click to zoom "
        f"out. {_resolution(data)}</p>",
        '<button id="zoom-reset" hidden>show the whole flight</button>',
        _plot("plot-pitch", has["attitude"], why("no attitude feedback in this input")),
        _plot("plot-yaw", has["attitude"], why("no attitude feedback in this input")),
        "<h2>Commanded and measured rates</h2>",
        _plot(
            "plot-rates",
            has["commanded"] or has["measured"],
            why("no gimbal_control command and no attitude feedback in this input"),
        ),
        "<h2>Feedback health</h2>",
        _plot("plot-health", has["feedback"], why("no gimbal feedback in this input")),
        "<h2>UAV</h2>",
        _plot("plot-altitude", has["altitude"], why("no UAV altitude (0x0000FF16) in this input")),
        _plot("plot-track", has["track"], "no UAV GPS position (0x0000FF15) in this input", True),
        "<h2>UAV status texts</h2>",
        tables.texts(data, zone),
        "<h2>Responses</h2>",
        tables.responses(data, zone),
        camera.camera_section(pictures, camera.shown_findings(data.findings.worst_first()), zone)
        if pictures is not None
        else "",
        judged,
        "<h2>Diagnostics</h2>",
        tables.diagnostics(data, zone),
    ]
    return "\n".join(
        [
            "<!DOCTYPE html>",
            '<html lang="en"><head><meta charset="utf-8">',
            '<meta name="viewport" content="width=device-width, initial-scale=1">',
            f"<title>{_e(title)}</title>",
            f"<style>{CSS}{camera.CSS if pictures is not None else ''}"
            f"{camera_judged.CSS if judged else ''}</style>",
            "</head><body>",
            *sections,
            f'<script id="report-data" type="application/json">{payload}</script>',
            f"<script>{chart_js}</script>",
            f"<script>{script}</script>",
            f"<script>{check_js}</script>",
            "</body></html>",
        ]
    )
