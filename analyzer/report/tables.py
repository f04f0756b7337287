"""The report's HTML tables: overview, findings per command and check, texts, diagnostics."""

from __future__ import annotations

import html
from typing import Any

from analyzer.analysis.findings import (
    ALL_VERDICTS,
    DEGRADED,
    HEALTHY,
    LOST,
    NOT_OBEYED,
    OBEYED,
    PARTIAL,
    UNKNOWN,
    VERDICTS,
)
from analyzer.report.collect import MAX_ROWS, ReportData
from analyzer.report.finding_groups import Group
from analyzer.timefmt import TimeZone, is_absolute

UNTIMED = (
    "the input carries no timestamps (a raw TCP/UART byte dump?), so responses cannot be "
    "timed; record with `gimbal-analyzer record` to get times"
)
EVERY_FINDING = (
    "Every finding, one per line, is in <code>gimbal-analyzer analyze FILE --json</code>, "
    "and in a recording's <code>/analysis/response</code> topic "
    "(<code>gimbal-analyzer convert</code> writes it)."
)


def _e(value: Any) -> str:
    return html.escape(str(value), quote=True)


def clock(t: float, zone: TimeZone, with_date: bool = False) -> str:
    """A time of the page, by the one time rule (analyzer.timefmt) in ``zone``: UTC with
    Z, or local time with --local-time; seconds for a relative time."""
    if not is_absolute(t):
        return f"{t:.3f} s"
    return zone.format_datetime(t) if with_date else zone.format_clock(t)


def _verdict(verdict: str) -> str:
    return f'<span class="v v-{_e(verdict)}">{_e(verdict.replace("_", " "))}</span>'


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


# The summary table's verdict columns: a command's verdict and the feedback's health word
# that ranks with it share a column.
COLUMNS = ((OBEYED, HEALTHY), (PARTIAL, DEGRADED), (NOT_OBEYED, LOST), (UNKNOWN,))


def _counts(counts: dict[str, int]) -> str:
    return ", ".join(f"{counts[v]:,} {v.replace('_', ' ')}" for v in ALL_VERDICTS if counts.get(v))


def overview(data: ReportData, settings: str, zone: TimeZone) -> str:
    rows: list[tuple[str, str]] = [("source", f"{_e(data.source)} ({_e(data.format_name)})")]
    if data.first is not None and data.last is not None:
        span = data.last - data.first
        rows.append(
            (
                "time range",
                f"{_e(clock(data.first, zone, True))} to {_e(clock(data.last, zone, True))} "
                f"({span:.1f} s)",
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
    rows.extend(_bus_rows(data, zone))
    verdicts = data.counts.verdicts  # the commands' findings, as analyze counts them
    rows.append(("verdicts", " ".join(f"{_verdict(v)} {verdicts.get(v, 0):,}" for v in VERDICTS)))
    rows.append(("feedback", _e(data.counts.health_line())))
    rows.append(("judged with", _e(settings)))
    body = "".join(f"<tr><td>{k}</td><td>{v}</td></tr>" for k, v in rows)
    return f'<table class="kv">{body}</table>'


def _bus_rows(data: ReportData, zone: TimeZone) -> list[tuple[str, str]]:
    """The CAN bus's worst state and when, its error frames by class, and what to do."""
    from analyzer.bus_hints import bus_hints

    worst = data.bus.worst()
    if worst is None:
        return []
    state, when, channel = worst
    at = f" at {_e(clock(when, zone, True))}" if when is not None else ""
    classes = ", ".join(f"{_e(k)} {n:,}" for k, n in data.bus.classes().most_common())
    rows = [
        ("CAN bus", f"worst {_e(state)}{at} on {_e(channel)}"),
        ("error frames", f"{data.bus.error_frames:,}: {classes}"),
    ]
    rows += [("hint", _e(hint)) for hint in bus_hints(data.bus, data.frames, zone)]
    return rows


def _number(key: str, form: str) -> Any:
    def cell(finding: dict[str, Any]) -> str:
        value = finding.get(key)
        return _e(format(value, form)) if isinstance(value, (int, float)) else ""

    return cell


# The figure columns of a group's examples, by check: (heading, numeric, cell maker).
_TARGET_COLUMNS = (
    ("target °", True, _number("target_deg", "g")),
    ("yaw reference", False, lambda f: _yaw_reference(f)),
    ("response s", True, _number("response_s", ".2f")),
    ("error °", True, _number("error_deg", ".2f")),
    ("sent", True, _number("command_count", ",")),
)
_STICK_COLUMNS = (
    ("pan ratio", True, _number("pan_ratio", ".2f")),
    ("tilt ratio", True, _number("tilt_ratio", ".2f")),
    ("lag s", True, _number("lag_s", ".2f")),
    ("commands", True, _number("command_count", ",")),
    ("every s", True, _number("interval_mean_s", ".3f")),
    ("longest pause s", True, _number("interval_max_s", ".2f")),
)
_FIGURES = {
    "rate": _STICK_COLUMNS,
    "repeat": _STICK_COLUMNS[3:],
    "stop": (("moved °", True, _number("moved_deg", ".1f")),),
    "tracking": (
        ("response s", True, _number("response_s", ".2f")),
        ("commands", True, _number("command_count", ",")),
        ("updates/s", True, _number("updates_hz", ".1f")),
        ("session s", True, _number("duration_s", ".1f")),
    ),
    "feedback": (
        ("messages/s", True, _number("feedback_hz", ".2f")),
        ("lost", True, _number("lost_messages", ",")),
        ("damaged", True, _number("crc_errors", ",")),
    ),
    "feedback_gap": (
        ("silence s", True, _number("gap_s", ".2f")),
        ("lost", True, _number("lost_messages", ",")),
    ),
}


def _figure_columns(check: str) -> tuple[tuple[str, bool, Any], ...]:
    return _FIGURES.get(check, _TARGET_COLUMNS)


def _example(
    finding: dict[str, Any], columns: tuple[tuple[str, bool, Any], ...], zone: TimeZone
) -> list[str]:
    return [
        _e(clock(float(finding["time"]), zone)),
        _verdict(str(finding["verdict"])),
        _e(finding.get("detail", "")),
        *(cell(finding) for _, _, cell in columns),
    ]


def _group(group: Group, zone: TimeZone) -> str:
    examples = group.examples()
    span = ""
    if group.first is not None and group.last is not None and group.total > 1:
        span = f", {_e(clock(group.first, zone))} to {_e(clock(group.last, zone))}"
    shown = (
        f"{len(examples)} examples of {group.total:,}"
        if len(examples) < group.total
        else f"all {group.total:,}"
    )
    head = (
        f'<h3 class="group" data-command="{_e(group.command)}" data-check="{_e(group.check)}">'
        f"{_e(group.command)} &middot; {_e(group.check)}: {group.total:,} "
        f'<span class="small">({_e(_counts(group.verdicts))}{span})</span></h3>'
        f'<p class="small">{shown}, the worst first:</p>'
    )
    figures = _figure_columns(group.check)
    heads = ["time", "verdict", "detail", *(h for h, _, _ in figures)]
    numeric = frozenset(3 + i for i, (_, num, _) in enumerate(figures) if num)
    return head + _rows([_example(f, figures, zone) for f in examples], heads, numeric)


def responses(data: ReportData, zone: TimeZone) -> str:
    """Findings per command and check: exact counts by verdict, the worst examples."""
    if data.untimed:
        return f'<p class="empty">{_e(UNTIMED)}</p>'
    groups = data.findings.ordered()
    if not groups:
        return '<p class="empty">no command with a visible effect, and no feedback</p>'
    rows = [
        [
            _e(g.command),
            _e(g.check),
            *(f"{sum(g.verdicts.get(v, 0) for v in column):,}" for column in COLUMNS),
            f"{g.total:,}",
        ]
        for g in groups
    ]
    words = [" / ".join(v.replace("_", " ") for v in column) for column in COLUMNS]
    head = ["command", "check", *words, "findings"]
    table = _rows(rows, head, frozenset(range(2, 3 + len(COLUMNS))))
    intro = (
        f'<p class="small">{data.findings.total:,} findings, counted per command and check; '
        f"below each, up to {data.findings.keep} examples, the worst first. {EVERY_FINDING}</p>"
    )
    return "\n".join([intro, table, *(_group(g, zone) for g in groups)])


def _yaw_reference(finding: dict[str, Any]) -> str:
    """'north' or 'airframe' over the reason, for a yaw target; empty otherwise."""
    if "yaw_reference" not in finding:
        return ""
    reason = finding.get("reference_reason", "")
    small = f'<br><span class="small">{_e(reason)}</span>' if reason else ""
    return _e(finding["yaw_reference"]) + small


def texts(data: ReportData, zone: TimeZone) -> str:
    """The flight controller's status texts (0x02008201 / 0x02008202)."""
    if not data.texts:
        return '<p class="empty">no status text from the flight controller in this input</p>'
    table = _rows([[_e(clock(t, zone)), _e(text)] for t, text in data.texts], ["time", "text"])
    if data.text_count > len(data.texts):
        table += f'<p class="small">the first {len(data.texts):,} of {data.text_count:,}</p>'
    return table


def diagnostics(data: ReportData, zone: TimeZone) -> str:
    if not data.diagnostics:
        return '<p class="empty">none: every frame decoded cleanly</p>'
    rows = [[_e(clock(t, zone)), _e(kind), _e(detail)] for t, kind, detail in data.diagnostics]
    table = _rows(rows, ["time", "kind", "detail"])
    total = sum(data.diagnostic_kinds.values())
    if total > len(data.diagnostics):
        table += f'<p class="small">the first {MAX_ROWS:,} of {total:,} are listed</p>'
    return table
