"""`table` and `fleet`: a fleet of simulated flights into Parquet, and the questions over it."""

from __future__ import annotations

import csv
import io
import json
import re
from pathlib import Path
from typing import Any

import duckdb
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from analyzer.fleet.columns import TOPIC_TABLES
from analyzer.fleet.rows import FileWork, file_rows
from analyzer.protocol.command_table import COMMANDS
from analyzer.protocol.feedback import ATTITUDE
from tests.fleet_flights import (
    DAMAGED,
    START,
    UNREADABLE,
    WEEK,
    built_fleet,
    cli,
    questions,
    recording,
    rows,
)


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    return built_fleet(tmp_path_factory)


def test_every_input_is_a_row_and_the_summary_counts_them(fleet: dict[str, Any]) -> None:
    assert "2 input(s), 2 added" in fleet["runs"]["A"]
    assert "4 input(s), 3 added" in fleet["runs"]["B"] and "1 with errors" in fleet["runs"]["B"]
    names = sorted(r["recording"] for r in rows(fleet["dataset"], "recordings"))
    assert names == sorted(fleet["files"])
    cut = recording(fleet["dataset"], UNREADABLE)
    assert cut["error"] == "cannot read {} as a capture: the pcap file header is cut off".format(
        fleet["files"][UNREADABLE]
    )
    assert cut["frames"] is None and cut["gimbal"] == "B"
    assert re.search(rf"error \S*{UNREADABLE}: cannot read", fleet["runs"]["B"])


@pytest.mark.parametrize(
    "name", ["a-clean.log", "a-clean-next-week.mcap", "b-crc.log", "b-deaf.log", DAMAGED]
)
def test_the_numbers_are_those_of_decode_info_and_analyze(fleet: dict[str, Any], name: str) -> None:
    path = str(fleet["files"][name])
    row = recording(fleet["dataset"], name)
    code, out, _ = cli("decode", path, "--summary", "--json")
    assert code == 0
    summary = json.loads(out)
    feedback = list(summary["feedback"].values())
    assert row["crc_errors"] == summary["crc_errors"]
    assert row["crc_checked"] == summary["crc_checked"]
    assert row["crc_error_rate"] == summary["crc_error_rate"]
    assert row["events"] == summary["events"]
    assert row["diagnostics"] == summary["diagnostics"]
    assert row["commands"] == summary["topics"].get("/gimbal/command", 0)
    assert row["feedback_messages"] == sum(f["messages"] for f in feedback)
    assert row["gaps"] == sum(f["gaps_over_threshold"] for f in feedback)
    assert row["longest_gap_s"] == max((f["longest_gap_s"] for f in feedback), default=None)
    for kind, count in summary["diagnostics_by_kind"].items():
        assert row[f"diag_{kind}"] == count
    if summary["last_time"]:
        assert row["start"].timestamp() == pytest.approx(summary["first_time"], abs=1e-6)
        assert row["end"].timestamp() == pytest.approx(summary["last_time"], abs=1e-6)
    if name.endswith(".mcap") and name != DAMAGED:
        code, out, _ = cli("info", path, "--json")
        info = json.loads(out)
        assert row["frames"] == info["input"]["frames"] > 0
        assert row["crc_errors"] == info["figures"]["crc_errors"]
        assert row["events"] == info["figures"]["events"]
    code, out, _ = cli("analyze", path, "--json")
    found = [json.loads(line) for line in out.splitlines()]
    mine = sorted(
        (r for r in rows(fleet["dataset"], "findings") if r["recording"] == name),
        key=lambda r: (r["time"], r["command"], r["check"]),
    )
    found.sort(key=lambda f: (f["time"], f["command"], f["check"]))
    assert len(mine) == len(found) == row["findings"]
    for verdict in ("obeyed", "partial", "not_obeyed", "unknown"):
        assert row[f"findings_{verdict}"] == sum(1 for f in found if f["verdict"] == verdict)
    for table_row, finding in zip(mine, found, strict=True):
        assert table_row["time"].timestamp() == pytest.approx(finding["time"], abs=1e-6)
        for key in (
            "command",
            "check",
            "verdict",
            "detail",
            "target_deg",
            "response_s",
            "error_deg",
            "yaw_reference",
            "reference_reason",
        ):
            assert table_row[key] == finding.get(key), key


def test_known_faults_show_where_they_were_made(fleet: dict[str, Any]) -> None:
    dataset = fleet["dataset"]
    clean = recording(dataset, "a-clean.log")
    assert clean["crc_errors"] == 0 and clean["gaps"] == 0 and clean["findings_not_obeyed"] == 0
    assert recording(dataset, "b-crc.log")["crc_errors"] > 0
    deaf = recording(dataset, "b-deaf.log")
    assert deaf["gaps"] == 1 and deaf["longest_gap_s"] >= 3.0
    tracking = [r for r in rows(dataset, "findings") if r["command"] == "tracking"]
    assert {r["recording"]: r["verdict"] for r in tracking} == {
        "a-clean.log": "obeyed",
        "a-clean-next-week.mcap": "obeyed",
        "b-crc.log": "obeyed",
        "b-deaf.log": "not_obeyed",
    }


def test_the_standard_questions(fleet: dict[str, Any]) -> None:
    dataset = fleet["dataset"]
    answers = questions(dataset)
    every = {r["recording"]: r for r in rows(dataset, "recordings")}
    b_read = [r for r in every.values() if r["gimbal"] == "B" and r["error"] is None]
    link = {r["gimbal"]: r for r in answers["link_by_gimbal"]}
    assert link["A"] == {
        "gimbal": "A", "flights": 2, "crc_errors": 0, "crc_protected": 106,
        "crc_error_rate": 0.0, "gaps": 0, "longest_gap_s": 0.5,
    }  # fmt: skip
    crc = sum(r["crc_errors"] for r in b_read)
    protected = sum(r["crc_checked"] + r["crc_errors"] for r in b_read)
    assert link["B"]["flights"] == 3 and link["B"]["crc_errors"] == crc
    assert link["B"]["crc_error_rate"] == round(crc / protected, 6)
    assert link["B"]["gaps"] == sum(r["gaps"] for r in b_read)
    assert every["b-deaf.log"]["gaps"] == 1  # the 3 s outage
    assert every["b-crc.log"]["gaps"] == 0  # a damaged message came: damaged, not lost
    weeks = {(r["week"], r["firmware"]): r["flights"] for r in answers["link_by_week_firmware"]}
    assert weeks == {
        ("2023-W46", "1.2"): 1,
        ("2023-W47", "1.2"): 1,
        ("2023-W46", "1.3"): 1,
        ("2023-W47", "1.3"): 1,
        (None, "1.3"): 1,
    }
    obedience = {(r["command"], r["gimbal"]): r for r in answers["obedience_by_gimbal"]}
    assert obedience[("tracking", "A")]["obeyed"] == 2
    assert obedience[("tracking", "B")]["not_obeyed"] == 1
    assert obedience[("tracking", "B")]["obeyed"] == 1
    assert all(r["command"] != "feedback" for r in answers["obedience_by_gimbal"])
    worst = answers["worst_flights"]
    assert worst[0]["recording"] == UNREADABLE and worst[0]["reason"].startswith("unreadable: ")
    assert {w["recording"] for w in worst} == {UNREADABLE, "b-crc.log", "b-deaf.log", DAMAGED}
    deaf = next(w for w in worst if w["recording"] == "b-deaf.log")
    assert "1 feedback gap(s), longest 3.5 s" in deaf["reason"]
    assert "1 finding(s) not obeyed" in deaf["reason"]  # tracking; the gap counted once
    damaged = next(w for w in worst if w["recording"] == DAMAGED)
    assert damaged["reason"] == "1 other diagnostic(s)"


def test_text_output_shows_the_same_answers(fleet: dict[str, Any]) -> None:
    code, out, _ = cli("fleet", str(fleet["dataset"]))
    assert code == 0
    assert "CRC error rate and feedback gaps per gimbal" in out
    assert re.search(r"^  b-cut\.pcap\s+B\s+1\.3\s+-\s+1000\s+unreadable: cannot read ", out, re.M)


def test_sql_csv_and_json(fleet: dict[str, Any]) -> None:
    dataset = str(fleet["dataset"])
    sql = "SELECT gimbal, count(*) AS flights, sum(frames) AS frames FROM recordings GROUP BY 1 ORDER BY 1"
    code, out, _ = cli("fleet", dataset, "--sql", sql, "--csv")
    assert code == 0
    table = list(csv.DictReader(io.StringIO(out)))
    every = rows(fleet["dataset"], "recordings")
    for gimbal in ("A", "B"):
        mine = [r for r in every if r["gimbal"] == gimbal]
        (line,) = [t for t in table if t["gimbal"] == gimbal]
        assert int(line["flights"]) == len(mine)
        assert int(line["frames"]) == sum(r["frames"] or 0 for r in mine)
    joined = (
        "SELECT r.gimbal, f.time FROM findings f JOIN recordings r USING (content_hash) "
        "WHERE f.verdict = 'not_obeyed' AND f.command = 'tracking'"
    )
    code, out, _ = cli("fleet", dataset, "--sql", joined, "--json")
    assert [json.loads(line) for line in out.splitlines()] == [
        {"gimbal": "B", "time": "2023-11-21T22:13:33Z"}
    ]
    assert START + WEEK + 13.0 == 1_700_604_813.0  # the tracking command of b-deaf.log


def test_columns_are_typed_from_the_command_table_and_layouts(fleet: dict[str, Any]) -> None:
    kinds = {
        "u8": pa.int64(),
        "u16": pa.int64(),
        "s16": pa.int64(),
        "s8": pa.int64(),
        "u32": pa.int64(),
        "s32": pa.int64(),
    }
    schema = pq.read_schema(next((fleet["dataset"] / "commands").glob("*.parquet")))
    for command in COMMANDS:
        for field in command.all_fields():
            expected = (
                pa.string() if field.labels is not None else
                pa.bool_() if field.boolean else
                kinds[field.kind] if field.div == 1 else pa.float64()
            )  # fmt: skip
            assert schema.field(field.name).type == expected, field.name
    attitude = pq.read_schema(next((fleet["dataset"] / "attitude").glob("*.parquet")))
    for field in ATTITUDE.layout.fields:
        assert field.name in attitude.names
    assert attitude.field("time").type == pa.timestamp("us", tz="UTC")
    findings = pq.read_schema(next((fleet["dataset"] / "findings").glob("*.parquet")))
    assert findings.field("yaw_reference").type == pa.string()
    assert findings.field("reference_reason").type == pa.string()
    assert set(TOPIC_TABLES.values()) >= {"commands", "attitude", "diagnostics", "findings"}


def test_bad_usage_is_one_line(fleet: dict[str, Any], tmp_path: Path) -> None:
    code, _, err = cli(
        "table", str(fleet["files"]["a-clean.log"]), "-o", str(tmp_path / "d"), "--tag", "frames=3"
    )
    assert (
        code == 2
        and err
        == "gimbal-analyzer table: error: --tag frames: that name is a column of the recordings table\n"
    )
    code, _, err = cli("table", str(tmp_path / "nothing"), "-o", str(tmp_path / "d"))
    assert code == 2 and "no such file or folder" in err
    code, _, err = cli("fleet", str(tmp_path))
    assert code == 2 and "holds no fleet dataset" in err
    code, _, err = cli("fleet", str(fleet["dataset"]), "--sql", "SELECT nope FROM recordings")
    assert (
        code == 2 and err.startswith("gimbal-analyzer fleet: error: SQL: ") and err.count("\n") == 1
    )


def test_duckdb_reads_the_dataset_directly(fleet: dict[str, Any]) -> None:
    """The dataset is plain Parquet: any DuckDB (or pandas, Spark...) reads it as it is."""
    pattern = str(fleet["dataset"] / "findings" / "*.parquet")
    ((count,),) = duckdb.sql(f"SELECT count(*) FROM read_parquet('{pattern}')").fetchall()
    assert count == len(rows(fleet["dataset"], "findings")) > 0


@settings(
    max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    data=st.binary(max_size=600),
    suffix=st.sampled_from([".log", ".mcap", ".pcap", ".bin", ".asc", ".blf"]),
)
def test_any_bytes_give_a_row_and_never_stop_the_fleet(
    tmp_path: Path, data: bytes, suffix: str
) -> None:
    path = tmp_path / f"input{suffix}"
    path.write_bytes(data)
    result = file_rows(FileWork(str(path), path.name, "h", len(data), (("gimbal", "X"),)))
    (row,) = result.tables["recordings"].to_pylist()
    assert row["recording"] == path.name and row["gimbal"] == "X"
    assert (row["error"] is None) == (result.error is None)
    if result.error is not None:
        assert set(result.tables) == {"recordings"} and "\n" not in result.error


@pytest.mark.slow
def test_fleet_report_loads_in_chromium_with_every_plot_drawn(
    fleet: dict[str, Any], tmp_path: Path
) -> None:
    from tests.test_report_command import canvases, load

    page = tmp_path / "fleet.html"
    code, _, err = cli("fleet", str(fleet["dataset"]), "--html", str(page))
    assert code == 0 and err.startswith(f"wrote {page}")
    text = page.read_text(encoding="utf-8")
    assert "http://" not in text.replace("http://www.w3.org", "") and "https://cdn" not in text
    dom, console = load(page, tmp_path)
    assert 'data-plots-ready="yes"' in dom, console
    drawn = canvases(dom)
    assert set(drawn) == {"plot-crc-week", "plot-gaps", "plot-verdicts", "plot-response"}
    for plot, (painted, points) in drawn.items():
        assert painted > 0 and points > 0, plot
    assert "b-cut.pcap" in dom and "Obedience per command and gimbal" in dom
    code, _, err = cli("fleet", str(fleet["dataset"]), "--html", str(page))
    assert code == 2 and "--force" in err


def test_times_follow_local_time_in_text_and_report_but_not_json(
    fleet: dict[str, Any], tmp_path: Path, india_time: None
) -> None:
    dataset = str(fleet["dataset"])
    code, utc, _ = cli("fleet", dataset)
    assert code == 0
    assert re.search(r"^  b-crc\.log .* 2023-11-14 22:13:20\.000Z ", utc, re.M)
    code, local, _ = cli("--local-time", "fleet", dataset)
    assert code == 0
    assert re.search(r"^  b-crc\.log .* 2023-11-15 03:43:20\.000\+05:30 ", local, re.M)
    assert "Z " not in local.split("The worst flights")[1]
    code, out, _ = cli("fleet", dataset, "--json", "--local-time")
    worst = [json.loads(line) for line in out.splitlines()]
    (crc,) = [w for w in worst if w.get("recording") == "b-crc.log"]
    assert crc["start"] == "2023-11-14T22:13:20Z"
    page = tmp_path / "local.html"
    code, _, _ = cli("fleet", dataset, "--html", str(page), "--local-time")
    assert code == 0
    text = page.read_text(encoding="utf-8")
    assert "Times are local time; weeks are ISO weeks in UTC." in text
    assert "2023-11-15 03:43:20.000+05:30 to 2023-11-22 03:43:46.000+05:30" in text
