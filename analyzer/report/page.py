"""The report as one self-contained HTML page: tables in HTML, plots drawn by inlined Chart.js."""

from __future__ import annotations

import html
import json
import time
from importlib import resources
from typing import Any

from analyzer import __version__, timefmt
from analyzer.analysis.findings import VERDICTS
from analyzer.report import camera
from analyzer.report.collect import MAX_ROWS, ReportData, thin

CHART_JS = "chart.umd.min.js"  # Chart.js 4.6.1, MIT (vendor/chart.js-LICENSE.md)
CHECK_JS = "plots_check.js"  # shared with the fleet report: what the page checks can read
TARGET_AXES = ("pitch", "yaw", "motor_yaw")

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
.small { font-size: 12px; color: #666; }
"""


def _clock(t: float, with_date: bool = False) -> str:
    """The one time rule (analyzer.timefmt): UTC with Z, or local time with --local-time."""
    if not timefmt.is_absolute(t):
        return f"{t:.3f} s"
    return timefmt.format_datetime(t) if with_date else timefmt.format_clock(t)


def _e(value: Any) -> str:
    return html.escape(str(value), quote=True)


def _verdict(verdict: str) -> str:
    return f'<span class="v v-{_e(verdict)}">{_e(verdict.replace("_", " "))}</span>'


def _plot(plot_id: str, has_data: bool, empty: str, square: bool = False) -> str:
    if not has_data:
        return f'<p class="empty">{_e(empty)}</p>'
    cls = "plot square" if square else "plot"
    return f'<div class="{cls}"><canvas id="{plot_id}"></canvas></div>'


def _rows(rows: list[list[str]], head: list[str], numeric: frozenset[int] = frozenset()) -> str:
    out = ["<table><tr>" + "".join(f"<th>{_e(h)}</th>" for h in head) + "</tr>"]
    for row in rows:
        cells = "".join(
            f'<td class="num">{c}</td>' if i in numeric else f"<td>{c}</td>"
            for i, c in enumerate(row)
        )
        out.append(f"<tr>{cells}</tr>")
    out.append("</table>")
    return "\n".join(out)


def _plot_data(data: ReportData) -> dict[str, Any]:
    start = data.first or 0.0

    def rel(rows: list[tuple[Any, ...]]) -> list[list[Any]]:
        return [[round(r[0] - start, 3), *(round(v, 3) for v in r[1:])] for r in thin(rows)]

    targets = []
    for f in data.findings:
        axis = str(f.get("axis", ""))
        if "target_deg" not in f:
            continue
        for part in axis.split("+"):
            if part in TARGET_AXES:
                what = f"{f['command']} {f['target_deg']:g}: {f['detail']}"
                targets.append(
                    [round(f["time"] - start, 3), f["target_deg"], f["verdict"], what, part]
                )
    return {
        "start": start,
        "span": round((data.last or start) - start, 3),
        "attitude": rel(data.attitude),
        "marks": [[round(t - start, 3), name] for t, name in thin(data.command_marks, 400)],
        "targets": targets,
        "commanded": rel(data.commanded_rates()),
        "measured": rel(data.measured_rates()),
        "feedback": rel(data.feedback_per_second()),
        "errors": rel(data.errors_per_second()),
        "altitude": rel(data.altitude),
        "track": [[round(e, 1), round(n, 1)] for e, n in thin(data.track_m())],
    }


def _overview(data: ReportData, settings: str) -> str:
    rows: list[tuple[str, str]] = [("source", f"{_e(data.source)} ({_e(data.format_name)})")]
    if data.first is not None and data.last is not None:
        span = data.last - data.first
        rows.append(
            (
                "time range",
                f"{_e(_clock(data.first, True))} to {_e(_clock(data.last, True))} ({span:.1f} s)",
            )
        )
    rows.append(
        ("events", ", ".join(f"{_e(t)} {n:,}" for t, n in sorted(data.topics.items())) or "none")
    )
    rows.append(
        ("commands", ", ".join(f"{_e(c)} {n:,}" for c, n in data.commands.most_common()) or "none")
    )
    kinds = data.diagnostic_kinds
    rows.append(
        ("diagnostics", ", ".join(f"{_e(k)} {n:,}" for k, n in kinds.most_common()) or "none")
    )
    rows.extend(_bus_rows(data))
    verdicts = data.verdicts()
    rows.append(("verdicts", " ".join(f"{_verdict(v)} {verdicts.get(v, 0)}" for v in VERDICTS)))
    per_command: dict[str, dict[str, int]] = {}
    for f in data.findings:
        per_command.setdefault(str(f["command"]), {}).setdefault(str(f["verdict"]), 0)
        per_command[str(f["command"])][str(f["verdict"])] += 1
    for command, counts in sorted(per_command.items()):
        words = ", ".join(f"{n} {v.replace('_', ' ')}" for v, n in counts.items())
        rows.append((f"&nbsp;&nbsp;{_e(command)}", _e(words)))
    rows.append(("judged with", _e(settings)))
    body = "".join(f"<tr><td>{k}</td><td>{v}</td></tr>" for k, v in rows)
    return f'<table class="kv">{body}</table>'


def _bus_rows(data: ReportData) -> list[tuple[str, str]]:
    """The CAN bus's worst state and when, its error frames by class, and what to do."""
    from analyzer.bus_hints import bus_hints

    worst = data.bus.worst()
    if worst is None:
        return []
    state, when, channel = worst
    at = f" at {_e(_clock(when, True))}" if when is not None else ""
    classes = ", ".join(f"{_e(k)} {n:,}" for k, n in data.bus.classes().most_common())
    rows = [
        ("CAN bus", f"worst {_e(state)}{at} on {_e(channel)}"),
        ("error frames", f"{data.bus.error_frames:,}: {classes}"),
    ]
    rows += [("hint", _e(hint)) for hint in bus_hints(data.bus, data.frames)]
    return rows


def _responses(data: ReportData) -> str:
    if not data.findings:
        return '<p class="empty">no command with a visible effect, and no feedback</p>'
    rows = []
    for f in sorted(data.findings, key=lambda f: f["time"]):
        rows.append(
            [
                _e(_clock(f["time"])),
                _e(f["command"]),
                _e(f["check"]),
                _verdict(str(f["verdict"])),
                _e(f["detail"]),
                _e(f"{f['target_deg']:g}") if "target_deg" in f else "",
                _yaw_reference(f),
                _e(f"{f['response_s']:.2f}") if "response_s" in f else "",
                _e(f"{f['error_deg']:.2f}") if "error_deg" in f else "",
            ]
        )
    head = ["time", "command", "check", "verdict", "detail", "target °", "yaw reference"]
    head += ["response s", "error °"]
    return _rows(rows, head, frozenset({5, 7, 8}))


def _yaw_reference(finding: dict[str, Any]) -> str:
    """'north' or 'airframe' over the reason, for a yaw target; empty otherwise."""
    if "yaw_reference" not in finding:
        return ""
    reason = finding.get("reference_reason", "")
    small = f'<br><span class="small">{_e(reason)}</span>' if reason else ""
    return _e(finding["yaw_reference"]) + small


def _diagnostics(data: ReportData) -> str:
    if not data.diagnostics:
        return '<p class="empty">none: every frame decoded cleanly</p>'
    rows = [[_e(_clock(t)), _e(kind), _e(detail)] for t, kind, detail in data.diagnostics]
    table = _rows(rows, ["time", "kind", "detail"])
    total = sum(data.diagnostic_kinds.values())
    if total > len(data.diagnostics):
        table += f'<p class="small">the first {MAX_ROWS:,} of {total:,} are listed</p>'
    return table


def render(data: ReportData, settings: str) -> str:
    """The whole page."""
    plots = _plot_data(data)
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
        f'<p class="sub">gimbal-analyzer {_e(__version__)}, made {generated}. Times are UTC. '
        "The protocol has no acknowledgements: each command is judged from the attitude "
        "feedback that followed it.</p>",
        notes,
        "<h2>Overview</h2>",
        _overview(data, settings),
        "<h2>Gimbal attitude</h2>",
        '<p class="small">Dashed lines: commands. Crosses: target angles, coloured by verdict.</p>',
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
        "<h2>Responses</h2>",
        _responses(data),
        camera.camera_section(data.pictures, data.findings),
        "<h2>Diagnostics</h2>",
        _diagnostics(data),
    ]
    return "\n".join(
        [
            "<!DOCTYPE html>",
            '<html lang="en"><head><meta charset="utf-8">',
            '<meta name="viewport" content="width=device-width, initial-scale=1">',
            f"<title>{_e(title)}</title>",
            f"<style>{CSS}{camera.CSS if data.pictures else ''}</style>",
            "</head><body>",
            *sections,
            f'<script id="report-data" type="application/json">{payload}</script>',
            f"<script>{chart_js}</script>",
            f"<script>{script}</script>",
            f"<script>{check_js}</script>",
            "</body></html>",
        ]
    )
