"""`table` runs one after another: known content skipped, killed runs tidied, URLs, new tags."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import pyarrow.parquet as pq
import pytest

from tests.fleet_flights import (
    START,
    TAGS,
    built_fleet,
    cli,
    recording,
    rows,
)
from tests.platforms import posix_signals, symlinks


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    return built_fleet(tmp_path_factory)


def test_second_run_adds_nothing(fleet: dict[str, Any]) -> None:
    dataset: Path = fleet["dataset"]
    before = {p: p.stat().st_mtime_ns for p in dataset.rglob("*.parquet")}
    code, out, _ = cli(
        "table", str(fleet["root"] / "flights" / "A"), "-o", str(dataset), *TAGS["A"]
    )
    assert code == 0
    assert "2 input(s), 0 added (0 rows), 2 skipped" in out
    assert f"skipped {fleet['files']['a-clean.log']}: already in {dataset}" in out
    after = {p: p.stat().st_mtime_ns for p in dataset.rglob("*.parquet")}
    assert after == before


def test_an_interrupted_run_leaves_whole_files_that_the_next_run_tidies(
    fleet: dict[str, Any], tmp_path: Path
) -> None:
    dataset = tmp_path / "dataset"
    code, _, _ = cli(
        "table", str(fleet["files"]["a-clean.log"]), "-o", str(dataset), "--workers", "1"
    )
    assert code == 0
    # What a run killed half way leaves: a temporary file, and tables of an input whose
    # recordings row was never written.
    (dataset / "commands" / ".partial-99-x.parquet").write_bytes(b"PAR1")
    orphan = dataset / "attitude" / ("0" * 64 + ".parquet")
    orphan.write_bytes((next((dataset / "attitude").glob("*.parquet"))).read_bytes())
    code, out, _ = cli("table", str(fleet["files"]["a-clean.log"]), "-o", str(dataset))
    assert code == 0
    assert "removed 2 unfinished file(s) of an interrupted run" in out
    assert not orphan.exists() and not list(dataset.rglob(".partial-*"))


def test_an_fsspec_url_gives_the_rows_of_the_file(fleet: dict[str, Any], tmp_path: Path) -> None:
    """Workers may read inputs by URL (s3://... through fsspec); file:// is the local case."""
    path = fleet["files"]["b-crc.log"]
    dataset = tmp_path / "by-url"
    code, _, err = cli("table", path.as_uri(), "-o", str(dataset), "--workers", "1")
    assert code == 0, err
    (row,) = rows(dataset, "recordings")
    mine = recording(fleet["dataset"], "b-crc.log")
    assert row["path"] == path.as_uri() and row["recording"] == "b-crc.log"
    same = ("content_hash", "frames", "crc_errors", "crc_error_rate", "gaps", "findings", "start")
    assert {k: row[k] for k in same} == {k: mine[k] for k in same}
    assert len(rows(dataset, "findings")) == mine["findings"]


def test_runs_with_other_tags_add_columns(fleet: dict[str, Any], tmp_path: Path) -> None:
    """A tag one run gave and another did not is a column, null where it was not given."""
    dataset = str(tmp_path / "mixed")
    files = fleet["files"]
    assert cli("table", str(files["a-clean.log"]), "-o", dataset, "--tag", "gimbal=A")[0] == 0
    assert cli("table", str(files["b-crc.log"]), "-o", dataset, "--tag", "aircraft=K9")[0] == 0
    sql = "SELECT recording, gimbal, aircraft FROM recordings ORDER BY 1"
    code, out, _ = cli("fleet", dataset, "--sql", sql, "--json")
    assert code == 0
    assert [json.loads(line) for line in out.splitlines()] == [
        {"recording": "a-clean.log", "gimbal": "A", "aircraft": None},
        {"recording": "b-crc.log", "gimbal": None, "aircraft": "K9"},
    ]
    page = tmp_path / "mixed.html"
    code, out, _ = cli("fleet", dataset, "--sql", sql, "--html", str(page))
    assert code == 0 and out.startswith(f"Query: {sql}\n")
    text = page.read_text(encoding="utf-8")
    assert (
        f"<h2>Query: {sql}</h2>" in text and "CRC error rate and feedback gaps per aircraft" in text
    )


@posix_signals
@pytest.mark.slow
def test_a_run_killed_with_sigkill_leaves_whole_files_and_the_next_run_completes(
    tmp_path: Path,
) -> None:
    from analyzer.sim.engine import SimConfig
    from analyzer.sim.offline import run_offline
    from tests.fleet_flights import SCRIPT, SECONDS, candump

    flights = tmp_path / "flights"
    flights.mkdir()
    for n in range(12):
        frames, _ = run_offline(SCRIPT, SECONDS, SimConfig(), start=START + n * 3600)
        candump(flights / f"f{n:02d}.log", frames)
    dataset = tmp_path / "dataset"
    root = Path(__file__).resolve().parent.parent
    command = [sys.executable, "-m", "analyzer", "table", str(flights), "-o", str(dataset)]
    child = subprocess.Popen(
        [*command, "--workers", "1"],
        stdout=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": str(root)},
        encoding="utf-8",
    )
    assert child.stdout is not None
    try:
        for line in child.stdout:
            if line.startswith("[3/12] added"):
                child.send_signal(signal.SIGKILL)
                break
    finally:
        child.kill()
        child.wait(30)
    assert child.returncode == -signal.SIGKILL
    for path in dataset.rglob("*.parquet"):
        if not path.name.startswith("."):
            pq.read_table(path)  # every file in place is whole
    done = len(list((dataset / "recordings").glob("*.parquet")))
    assert 3 <= done < 12
    code, out, err = cli("table", str(flights), "-o", str(dataset), "--workers", "1")
    assert code == 0, err
    assert f"12 input(s), {12 - done} added" in out and f"{done} skipped" in out
    assert not list(dataset.rglob(".partial-*"))
    code, out, _ = cli(
        "fleet", str(dataset), "--sql", "SELECT count(*) AS n FROM recordings", "--csv"
    )
    assert out == "n\n12\n"
    code, out, _ = cli(
        "fleet",
        str(dataset),
        "--sql",
        "SELECT count(DISTINCT content_hash) AS n FROM attitude",
        "--csv",
    )
    assert out == "n\n12\n"


@symlinks
def test_a_failed_input_is_skipped_next_time_unless_retried(
    fleet: dict[str, Any], tmp_path: Path
) -> None:
    """An input that cannot be read at all (here a link to nothing) or fails to decode is
    a row with its error; the next runs skip it and say why, --retry-failed tries again."""
    flights = tmp_path / "flights"
    flights.mkdir()
    lost = flights / "lost.log"
    lost.symlink_to(flights / "elsewhere.log")
    cut = flights / "b-cut.pcap"
    cut.write_bytes(fleet["files"]["b-cut.pcap"].read_bytes())
    dataset = tmp_path / "dataset"
    args = ("table", str(lost), str(cut), "-o", str(dataset), "--workers", "1")
    code, out, err = cli(*args)
    assert code == 1 and "2 input(s), 0 added (0 rows), 0 skipped" in out
    assert (
        err == "gimbal-analyzer table: error: every input to add failed (2); their rows say why\n"
    )
    assert "2 with errors" in out
    row = recording(dataset, "lost.log")
    assert row["error"].startswith(f"cannot read {lost}: ") and row["frames"] is None
    before = {p: p.stat().st_mtime_ns for p in dataset.rglob("*.parquet")}

    code, out, _ = cli(*args)
    assert code == 0
    assert f"skipped {lost}: failed before ({row['error']}); --retry-failed tries again" in out
    cut_error = recording(dataset, "b-cut.pcap")["error"]
    assert f"skipped {cut}: failed before ({cut_error}); --retry-failed tries again" in out
    assert "0 added (0 rows), 2 skipped (content already there) (2 had failed: " in out
    assert {p: p.stat().st_mtime_ns for p in dataset.rglob("*.parquet")} == before

    code, out, _ = cli(*args, "--retry-failed")
    assert code == 1
    assert f"retrying {lost}: it failed before ({row['error']})" in out
    assert f"retrying {cut}: it failed before (cannot read {cut} as a capture: " in out
    assert "0 added (0 rows), 0 skipped" in out and "2 with errors" in out
    assert sorted(r["recording"] for r in rows(dataset, "recordings")) == ["b-cut.pcap", "lost.log"]

    # The link leads somewhere now: the next run reads it, and its error row goes.
    (flights / "elsewhere.log").write_bytes(fleet["files"]["a-clean.log"].read_bytes())
    code, out, _ = cli(*args)
    assert code == 0 and "1 added" in out
    (row,) = [r for r in rows(dataset, "recordings") if r["recording"] == "lost.log"]
    assert (
        row["error"] is None
        and row["frames"] == recording(fleet["dataset"], "a-clean.log")["frames"]
    )
    assert len(rows(dataset, "recordings")) == 2
