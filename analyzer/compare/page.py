"""`compare --html`: both attitude tracks on one time axis and the pairs, in the report's style."""

from __future__ import annotations

import json
import time
from importlib import resources

from analyzer.check.output import STEPS_CSS
from analyzer.compare.figures import Rule
from analyzer.compare.judged import Judged
from analyzer.compare.output import axis_words, figures_text, sides, verdict_line
from analyzer.compare.pairs import Pair
from analyzer.report.page import CHART_JS, CHECK_JS, CSS, _e, _plot, _rows
from analyzer.timefmt import UTC, TimeZone
from analyzer.version import __version__

PAGE_CSS = ".differs { color: #d62728; font-weight: 600; } .same { color: #2ca02c; }"


def _verdict(verdict: str | None) -> str:
    if verdict is None:
        return "-"
    word = _e(verdict.replace("_", " "))
    return f'<span class="v v-{_e(verdict)} st-{_e(verdict)}">{word}</span>'


def _plot_data(a: Judged, b: Judged, pairs: list[Pair]) -> dict[str, object]:
    def rows(one: Judged, other: Judged) -> list[list[float]]:
        return [[round(t, 3), round(p, 2), round(y, 2)] for t, p, y in one.track(other)]

    return {
        "a": rows(a, b),
        "b": rows(b, a),
        "differ": [
            [round(p.at, 3), f"{p.first.kind} {p.first.command}"] for p in pairs if p.differs
        ],
    }


def render(
    a: Judged, b: Judged, pairs: list[Pair], rules: tuple[Rule, ...], zone: TimeZone = UTC
) -> str:
    """The whole page, self-contained (Chart.js inlined as in the flight report); the time
    it was made in ``zone``."""
    plots = _plot_data(a, b, pairs)
    chart_js = (resources.files("analyzer.report") / "vendor" / CHART_JS).read_text("utf-8")
    check_js = (resources.files("analyzer.report") / CHECK_JS).read_text("utf-8")
    script = (resources.files("analyzer.compare") / "compare.js").read_text("utf-8")
    payload = json.dumps(plots, separators=(",", ":")).replace("</", "<\\/")
    has = bool(plots["a"] or plots["b"])
    title = f"Comparison: {a.name} and {b.name}"
    generated = zone.format_datetime(time.time())
    table = []
    for pair in pairs:
        first = pair.first
        word = (
            '<span class="differs">differs</span>'
            if pair.differs
            else '<span class="same">same</span>'
        )
        table.append(
            [
                _e(first.kind),
                _e(first.command),
                f"{pair.a.at:.2f}" if pair.a else "-",
                f"{pair.b.at:.2f}" if pair.b else "-",
                _verdict(pair.a.verdict if pair.a else None),
                _verdict(pair.b.verdict if pair.b else None),
                _e(figures_text(pair, rules)),
                word + "".join(f"<br>{_e(w)}" for w in pair.why),
            ]
        )
    head = ["kind", "command", "A s", "B s", "verdict A", "verdict B", "figures A | B", ""]
    sections = [
        f"<h1>{_e(title)}</h1>",
        f'<p class="sub">gimbal-analyzer {_e(__version__)}, made {_e(generated)}. Both '
        "recordings are judged by the response analysis; their judged commands are paired "
        "by kind and order.</p>",
        '<table class="kv">'
        + "".join(f"<tr><td>{side}</td><td>{_e(text)}</td></tr>" for side, text in sides(a, b))
        + "</table>",
        f'<p class="sub">{_e(verdict_line(pairs) if pairs else "nothing to compare")}</p>',
        "<h2>Gimbal attitude</h2>",
        f'<p class="small">{_e(axis_words(a, b).capitalize())}. A solid, B dashed; red lines: '
        "the pairs that differ.</p>",
        _plot("plot-pitch", has, "no attitude feedback in either"),
        _plot("plot-yaw", has, "no attitude feedback in either"),
        "<h2>Pairs</h2>",
        _rows(table, head, frozenset({2, 3})) if table else '<p class="empty">no pair</p>',
    ]
    return "\n".join(
        [
            "<!DOCTYPE html>",
            '<html lang="en"><head><meta charset="utf-8">',
            '<meta name="viewport" content="width=device-width, initial-scale=1">',
            f"<title>{_e(title)}</title>",
            f"<style>{CSS}{STEPS_CSS}{PAGE_CSS}</style>",
            "</head><body>",
            *sections,
            f'<script id="compare-data" type="application/json">{payload}</script>',
            f"<script>{chart_js}</script>",
            f"<script>{script}</script>",
            f"<script>{check_js}</script>",
            "</body></html>",
        ]
    )
