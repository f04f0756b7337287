"""How the check's results are shown: a table as it goes, JSON lines, the report's steps table."""

from __future__ import annotations

import contextlib
import html
import json
from typing import IO, Any

from analyzer.check.judge import StepResult
from analyzer.protocol.check_fields import FAIL, PASS, SKIPPED

# figure -> (label, format) in the order the table shows them
FIGURE_TEXT: tuple[tuple[str, str, str], ...] = (
    ("period_s", "period", "{:.2f} s"),
    ("messages", "messages", "{:d}"),
    ("lost", "lost", "{:d}"),
    ("crc_errors", "CRC errors", "{:d}"),
    ("slew_dps", "slew", "{:.1f} deg/s"),
    ("rate_dps", "rate", "{:.1f} deg/s"),
    ("asked_dps", "asked", "{:.1f} deg/s"),
    ("latency_s", "latency", "{:.2f} s"),
    ("settle_s", "settle", "{:.2f} s"),
    ("overshoot_deg", "overshoot", "{:.1f} deg"),
    ("error_deg", "error", "{:.2f} deg"),
    ("scale", "scale", "x{:.3g}"),
    ("scale_back", "back", "x{:.3g}"),
)
WIDTH = {"step": 13, "verdict": 8}


def figures_text(figures: dict[str, Any]) -> str:
    """'slew 60.1 deg/s, latency 0.05 s, ...' in a fixed order."""
    parts = []
    for key, label, fmt in FIGURE_TEXT:
        value = figures.get(key)
        if value is not None:
            parts.append(f"{label} {fmt.format(value)}")
    return ", ".join(parts)


class TablePrinter:
    """One line per step as it is decided, under a header; the detail on the next line."""

    def __init__(self, stream: IO[str]) -> None:
        self.stream = stream
        self.header = False

    def __call__(self, result: StepResult) -> None:
        if not self.header:
            self.header = True
            self.stream.write(
                f"{'step':<{WIDTH['step']}} {'verdict':<{WIDTH['verdict']}} figures\n"
            )
        figures = figures_text(result.figures) or "-"
        self.stream.write(
            f"{result.step:<{WIDTH['step']}} {result.verdict:<{WIDTH['verdict']}} {figures}\n"
            f"{'':<{WIDTH['step']}} {'':<{WIDTH['verdict']}} {result.detail}\n"
        )
        self.stream.flush()


class JsonPrinter:
    """One JSON object per step: step, verdict, detail and the figures as top-level keys."""

    def __init__(self, stream: IO[str]) -> None:
        self.stream = stream

    def __call__(self, result: StepResult) -> None:
        self.stream.write(json.dumps(result.fields()) + "\n")
        self.stream.flush()


def summary(results: list[StepResult]) -> str:
    """'8 passed, 1 failed, 1 skipped' ."""
    counts = {v: sum(1 for r in results if r.verdict == v) for v in (PASS, FAIL, SKIPPED)}
    failed = [r.step for r in results if r.verdict == FAIL]
    text = f"{counts[PASS]} passed, {counts[FAIL]} failed, {counts[SKIPPED]} skipped"
    return text + (f" ({', '.join(failed)})" if failed else "")


STEPS_CSS = (
    ".st-pass { background: #2ca02c; } .st-fail { background: #d62728; } "
    ".st-skipped { background: #888; }"
)


def steps_table_html(results: list[StepResult], title: str) -> str:
    """The steps as an HTML section for the top of the flight report."""
    e = html.escape
    rows = []
    for r in results:
        verdict = f'<span class="v st-{e(r.verdict)}">{e(r.verdict)}</span>'
        rows.append(
            f"<tr><td>{e(r.step)}</td><td>{verdict}</td>"
            f"<td>{e(figures_text(r.figures))}</td><td>{e(r.detail)}</td></tr>"
        )
    head = "<tr><th>step</th><th>verdict</th><th>figures</th><th>detail</th></tr>"
    return (
        f"<style>{STEPS_CSS}</style><h2>{e(title)}</h2>"
        f'<p class="sub">{e(summary(results))}</p>'
        f'<table id="check-steps">{head}{"".join(rows)}</table>'
    )


def result_from_fields(fields: dict[str, Any]) -> StepResult:
    """A /check/steps message back as a StepResult (figures: the keys that are figures)."""
    from analyzer.protocol.check_fields import FIGURES

    return StepResult(
        step=str(fields.get("step", "")),
        verdict=str(fields.get("verdict", "")),
        detail=str(fields.get("detail", "")),
        figures={k: v for k, v in fields.items() if k in FIGURES},
        index=int(fields.get("index", 0)),
        started_at=float(fields.get("started_at", 0.0)),
        duration_s=float(fields.get("duration_s", 0.0)),
        findings=[str(f) for f in fields.get("findings", [])],
    )


def recorded_steps(path: str) -> list[StepResult]:
    """The steps of a recording `check` made, in order (none for any other recording)."""
    from analyzer.mcapio.read.reader import McapRecording
    from analyzer.protocol.types import TOPIC_CHECK_STEPS

    results = []
    for message in McapRecording(path).messages({TOPIC_CHECK_STEPS}):
        with contextlib.suppress(ValueError, TypeError):
            fields = json.loads(message.data)
            if isinstance(fields, dict):
                results.append(result_from_fields(fields))
    return results


def recorded_steps_html(path: str) -> str:
    """The steps table of a recording `check` made ('' for any other recording)."""
    results = recorded_steps(path)
    return steps_table_html(results, "Bench check") if results else ""
