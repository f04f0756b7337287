"""A report of a long, dense flight stays small and opens in a browser with its plots drawn.

The flight is the benchmark's dense bus mix (every value changing from frame to frame) at
200,000 frames, a tenth of the 2M-frame flight the report must hold to 10 MB: this one is
held to a tenth of that. Its findings are counted exactly as ``analyze`` counts them.
"""

from __future__ import annotations

import json
import re
from collections import Counter
from pathlib import Path
from typing import Any

import pytest

from analyzer.cli import main
from analyzer.report.decimate import ATTITUDE_BUCKETS, FINE_BUCKETS
from benchmarks.decode_speed import write_log
from tests.test_report_charts import axes, embedded
from tests.test_report_command import canvases, load

pytestmark = pytest.mark.slow  # a long flight's report, in Chromium

FRAMES = 200_000
FULL_FRAMES = 2_000_000
FULL_LIMIT = 10_000_000  # bytes of HTML at FULL_FRAMES


@pytest.fixture(scope="module")
def dense(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """The dense flight's log and its report."""
    folder = tmp_path_factory.mktemp("dense")
    log = folder / "dense.log"
    write_log(log, FRAMES, "dense")
    page = folder / "dense.html"
    assert main(["report", str(log), "-o", str(page)]) == 0
    return log, page


def test_the_report_of_a_long_flight_is_small(dense: tuple[Path, Path]) -> None:
    _, page = dense
    assert page.stat().st_size <= FULL_LIMIT * FRAMES / FULL_FRAMES
    data = embedded(page)
    assert data["span"] == pytest.approx(100.0, abs=0.1)  # 4,000 blocks of 25 ms
    for name, buckets in (
        ("attitude", ATTITUDE_BUCKETS),
        ("measured", ATTITUDE_BUCKETS),
        ("commanded", FINE_BUCKETS),
    ):
        columns = len(data[name][0]) - 1
        assert len(data[name]) <= 2 * columns * buckets, name
    # 4,000 feedback messages: each kept, so a zoom shows every one
    assert len(data["attitude"]) == 4000
    # 36,000 stick commands: the extremes of each time bucket, not every command
    assert 6000 < len(data["commanded"]) < 36000
    text = page.read_text(encoding="utf-8")
    assert "--json</code>" in text and "/analysis/response</code>" in text


def test_findings_are_counted_exactly_as_analyze_counts_them(
    dense: tuple[Path, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    log, page = dense
    capsys.readouterr()
    assert main(["analyze", str(log), "--json"]) == 0
    found = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    expected = Counter((f["command"], f["check"], f["verdict"]) for f in found)
    text = page.read_text(encoding="utf-8")
    head = re.search(r"<tr><th>command</th><th>check</th>(.*?)</tr>", text)
    assert head
    columns = re.findall(r"<th>([a-z /]+)</th>", head.group(1))
    assert columns[:4] == ["obeyed / healthy", "partial / degraded", "not obeyed / lost", "unknown"]
    # a command's verdict, or the feedback's health word, of each column
    words = [[w.replace(" ", "_") for w in c.split(" / ")] for c in columns[:4]]
    counted: Counter[tuple[str, str, str]] = Counter()
    table = text.split("<h2>Responses</h2>")[1].split("</table>")[0]
    for row in re.findall(r"<tr><td>([^<]+)</td><td>([^<]+)</td>(.*?)</tr>", table):
        numbers = re.findall(r'<td class="num">([\d,]+)</td>', row[2])
        for word, number in zip(words, numbers, strict=False):
            verdict = word[-1] if row[0] == "feedback" else word[0]
            if int(number.replace(",", "")):
                counted[row[0], row[1], verdict] = int(number.replace(",", ""))
    assert counted == expected
    # 100 s of a pilot's stick: a finding per movement (and per cadence or stop), not one
    # per command
    movements = sum(n for (c, check, _), n in expected.items() if check == "rate")
    assert 20 < movements < 60
    # a bounded list of examples per group, with their times, the worst first
    examples = re.findall(r"(\d+) examples of ([\d,]+), the worst first", text)
    assert examples and all(int(n) <= 12 for n, _ in examples)


def test_the_long_flight_opens_in_chromium_with_every_plot_drawn(
    dense: tuple[Path, Path], tmp_path: Path
) -> None:
    _, page = dense
    dom, console = load(page, tmp_path)
    assert console == [] and 'data-plots-ready="yes"' in dom
    drawn = canvases(dom)
    assert sorted(drawn) == ["plot-health", "plot-pitch", "plot-rates", "plot-track", "plot-yaw"]
    for plot, (painted, points) in drawn.items():
        assert painted > 500 and points > 50, plot
    data = embedded(page)
    pitch = axes(dom)["plot-pitch"]["points"]
    # the view of 4,000 samples: fewer points, the same highest and lowest pitch
    assert 800 < len(pitch) < len(data["attitude"])
    assert max(p[1] for p in pitch) == max(r[1] for r in data["attitude"])
    assert min(p[1] for p in pitch) == min(r[1] for r in data["attitude"])


def test_a_zoom_into_the_long_flight_shows_every_sample_in_range(
    dense: tuple[Path, Path], tmp_path: Path
) -> None:
    _, page = dense
    dom, console = load(page, tmp_path, "#zoom=40,50")
    assert console == [] and 'data-zoom="40.000,50.000"' in dom
    data: dict[str, Any] = embedded(page)
    inside = {(r[0], r[1]) for r in data["attitude"] if 40 <= r[0] <= 50}
    shown = {(p[0], p[1]) for p in axes(dom)["plot-pitch"]["points"] if 40 <= p[0] <= 50}
    assert len(inside) == 400 and shown == inside
