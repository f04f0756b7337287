"""What a libFuzzer run says of itself: executions, their rate, coverage, what it found."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

# libFuzzer's status lines: "#1234  INITED cov: 567 ft: 890 corp: 12/3Kb ..." and its
# final statistics (-print_final_stats=1): "stat::average_exec_per_sec: 45".
_STATUS = re.compile(r"^#(\d+)\s+(\w+)\s+cov: (\d+) ft: (\d+) corp: (\d+)/", re.M)
_STAT = re.compile(r"^stat::(\w+):\s+(\d+)", re.M)
_SECONDS = re.compile(r"^Done \d+ runs in (\d+) second", re.M)
FINDINGS = ("crash-", "timeout-", "oom-", "leak-", "slow-unit-")


@dataclass
class Figures:
    """One target's run."""

    target: str
    executions: int = 0
    seconds: int = 0
    exec_per_s: int = 0
    coverage_start: int = 0  # edges covered by the seeds (and the regression inputs)
    coverage: int = 0  # edges covered at the end
    features: int = 0
    corpus: int = 0  # inputs kept (each adds coverage)
    peak_rss_mb: int = 0
    found: list[str] = field(default_factory=list)  # inputs saved as crashes / hangs / OOMs
    exit_code: int = 0  # of the process that ran it (a seed that crashes: no input saved)

    @property
    def ok(self) -> bool:
        return not self.found and self.exit_code == 0


def finds(work: Path) -> list[str]:
    """The inputs libFuzzer saved in ``work``: crashes, hangs, memory hogs."""
    return sorted(p.name for p in work.iterdir() if p.name.startswith(FINDINGS))


def parse(target: str, log: str) -> Figures:
    """The figures of a run from libFuzzer's output."""
    figures = Figures(target)
    for number, kind, cov, ft, corp in _STATUS.findall(log):
        if kind == "INITED":
            figures.coverage_start = int(cov)
        figures.executions = max(figures.executions, int(number))
        figures.coverage, figures.features, figures.corpus = int(cov), int(ft), int(corp)
    stats = {name: int(value) for name, value in _STAT.findall(log)}
    figures.executions = stats.get("number_of_executed_units", figures.executions)
    figures.exec_per_s = stats.get("average_exec_per_sec", 0)
    figures.peak_rss_mb = stats.get("peak_rss_mb", 0)
    done = _SECONDS.search(log)
    figures.seconds = int(done.group(1)) if done else 0
    return figures


HEADINGS = ("target", "executions", "exec/s", "coverage (edges)", "corpus", "peak RSS", "found")


def row(figures: Figures) -> tuple[str, ...]:
    return (
        figures.target,
        f"{figures.executions:,}",
        f"{figures.exec_per_s:,}",
        f"{figures.coverage_start:,} -> {figures.coverage:,}",
        f"{figures.corpus:,}",
        f"{figures.peak_rss_mb:,} MB",
        ", ".join(figures.found) or "nothing",
    )


def table(runs: list[Figures], *, markdown: bool = False) -> str:
    """The runs as a plain-text table, or a Markdown one (for the manual)."""
    rows = [HEADINGS, *map(row, runs)]
    if markdown:
        lines = ["| " + " | ".join(cells) + " |" for cells in rows]
        lines.insert(1, "|" + "|".join("---" for _ in HEADINGS) + "|")
        return "\n".join(lines)
    widths = [max(len(cells[i]) for cells in rows) for i in range(len(HEADINGS))]
    return "\n".join(
        "  ".join(cell.ljust(width) for cell, width in zip(cells, widths, strict=True)).rstrip()
        for cells in rows
    )
