"""`table` and `fleet` say what happened: exit codes, failures, tags, one CSV per question,
the CRC rate's one unit, and rows streamed into Parquet row groups as they come."""

from __future__ import annotations

import csv
import io
import json
import shutil
import socket
import time
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from analyzer.fleet import column_sink
from analyzer.fleet.column_sink import CollectedTables, ColumnSink
from analyzer.fleet.columns import CRC_RATE_UNIT
from analyzer.fleet.rows import FileWork, error_text, file_rows
from analyzer.mcapio.read.file_end import RecordingError
from analyzer.pipeline import Batch
from analyzer.protocol.types import TOPIC_GIMBAL_ATTITUDE, Event
from tests.fleet_flights import built_fleet, cli, questions, recording, rows


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    return built_fleet(tmp_path_factory)


def test_a_run_whose_every_input_failed_exits_1(tmp_path: Path) -> None:
    empty = tmp_path / "empty.mcap"
    empty.write_bytes(b"")
    code, out, err = cli("table", str(empty), "-o", str(tmp_path / "fleet"), "--workers", "1")
    assert code == 1
    assert f"error {empty}: {empty}: an empty file" in out
    assert (
        err == "gimbal-analyzer table: error: every input to add failed (1); their rows say why\n"
    )


def test_errors_never_carry_an_exception_class_name(tmp_path: Path) -> None:
    assert error_text(RecordingError("x.mcap: not an MCAP file")) == "x.mcap: not an MCAP file"
    assert error_text(ValueError("bad\nsecond line")) == "bad"
    assert error_text(MemoryError()) == "out of memory"
    text = tmp_path / "notes.mcap"
    text.write_text("hello, this is not a recording\n", encoding="utf-8")
    result = file_rows(FileWork(str(text), text.name, "h", 10))
    assert result.error == f"{text}: not an MCAP file"


def test_a_local_run_does_not_say_where_tasks_ran(fleet: dict[str, Any]) -> None:
    assert all("tasks ran on" not in out for out in fleet["runs"].values())


def test_an_unreachable_scheduler_fails_in_seconds(tmp_path: Path) -> None:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        nobody = f"tcp://127.0.0.1:{sock.getsockname()[1]}"
    flight = tmp_path / "f.log"
    flight.write_text("(1700000000.000000) can0 00000000#00\n", encoding="utf-8")
    began = time.monotonic()
    code, out, err = cli("table", str(flight), "-o", str(tmp_path / "fleet"), "--dask", nobody)
    assert time.monotonic() - began < 10  # the client alone retries for 30 s
    assert code == 2 and out == ""
    assert err == (
        f"gimbal-analyzer table: error: cannot reach the Dask scheduler at {nobody}: "
        "connection refused (is the scheduler running, on that port?)\n"
    )
    assert not (tmp_path / "fleet").exists()


def test_same_content_with_other_tags_warns_and_retag_replaces(
    fleet: dict[str, Any], tmp_path: Path
) -> None:
    dataset = tmp_path / "fleet"
    shutil.copytree(fleet["dataset"], dataset)
    flight = fleet["files"]["a-clean.log"]
    args = ("table", str(flight), "-o", str(dataset), "--tag", "gimbal=C", "--workers", "1")
    code, out, err = cli(*args)
    assert code == 0 and f"skipped {flight}: already in {dataset}" in out
    assert err == (
        f"gimbal-analyzer table: warning: {flight} is in {dataset} with the tags "
        "gimbal=A firmware=1.2, not gimbal=C: kept; --retag replaces them\n"
    )
    assert recording(dataset, "a-clean.log")["gimbal"] == "A"

    code, out, err = cli(*args, "--retag")
    assert code == 0 and err == ""
    assert f"retagged {flight}: gimbal=C (was gimbal=A firmware=1.2)" in out
    row = recording(dataset, "a-clean.log")
    assert row["gimbal"] == "C" and row["firmware"] is None
    assert row["frames"] == recording(fleet["dataset"], "a-clean.log")["frames"]
    # The same tags again: nothing to say.
    code, out, err = cli(*args)
    assert code == 0 and err == ""
    links = {r["gimbal"]: r for r in questions(dataset)["link_by_gimbal"]}
    assert links["C"]["flights"] == 1 and links["A"]["flights"] == 1


def test_csv_is_one_table_per_question(fleet: dict[str, Any]) -> None:
    dataset = str(fleet["dataset"])
    code, out, err = cli("fleet", dataset, "--csv")
    assert code == 2 and out == ""
    assert err.startswith(
        "gimbal-analyzer fleet: error: --csv writes one table: choose it with --question NAME, "
        "one of: link_by_gimbal, "
    )
    assert "worst_flights" in err and err.count("\n") == 1
    code, out, _ = cli("fleet", dataset, "--question", "worst_flights", "--csv")
    assert code == 0
    table = list(csv.DictReader(io.StringIO(out)))
    wanted = questions(fleet["dataset"])["worst_flights"]
    assert [r["recording"] for r in table] == [r["recording"] for r in wanted]
    assert list(table[0]) == list(wanted[0])
    code, out, _ = cli("fleet", dataset, "--question", "worst_flights", "--json")
    assert [json.loads(line)["recording"] for line in out.splitlines()] == [
        r["recording"] for r in wanted
    ]
    code, _, err = cli("fleet", dataset, "--question", "nothing")
    assert code == 2 and err.startswith("gimbal-analyzer fleet: error: --question nothing: no ")


def test_the_crc_rate_has_one_unit_everywhere(fleet: dict[str, Any]) -> None:
    """A fraction of the CRC-checked messages in the table, the answers and the reasons."""
    files = sorted((fleet["dataset"] / "recordings").glob("*.parquet"))
    field = pq.read_schema(files[0]).field("crc_error_rate")
    assert field.metadata == {b"unit": CRC_RATE_UNIT.encode()}
    row = recording(fleet["dataset"], "b-crc.log")
    assert 0 < row["crc_error_rate"] < 1
    (worst,) = [
        r for r in questions(fleet["dataset"])["worst_flights"] if r["recording"] == "b-crc.log"
    ]
    assert f"CRC error rate {round(row['crc_error_rate'], 4)}" in worst["reason"]
    assert "%" not in worst["reason"]


class _Spy:
    """A TablesOut that notes when each row group arrives."""

    def __init__(self) -> None:
        self.groups: list[tuple[str, int]] = []

    def write(self, name: str, table: pa.Table) -> None:
        self.groups.append((name, table.num_rows))

    def discard(self, name: str) -> None:
        self.groups = [g for g in self.groups if g[0] != name]


def test_rows_leave_the_sink_a_row_group_at_a_time() -> None:
    spy = _Spy()
    sink = ColumnSink(spy, "r", "h", group_rows=100)
    for n in range(7):
        events = [
            Event(TOPIC_GIMBAL_ATTITUDE, 1_700_000_000 + n * 60 + i * 0.5, "can0", {"pitch_deg": i})
            for i in range(60)
        ]
        sink.handle(Batch(events=events))
        held = sum(c.rows for c in sink.tables.values())
        assert held < 100  # never more than one row group waits in memory
    assert spy.groups == [("attitude", 100)] * 4
    sink.close()
    assert spy.groups[-1] == ("attitude", 20) and sink.rows == 420


@pytest.mark.slow
def test_row_groups_give_the_same_dataset_and_answers(
    fleet: dict[str, Any], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(column_sink, "GROUP_ROWS", 2)
    flights = fleet["root"] / "flights"
    dataset = tmp_path / "fleet"
    for folder, tags in (("A", ("gimbal=A", "firmware=1.2")), ("B", ("gimbal=B", "firmware=1.3"))):
        tag_args = [a for t in tags for a in ("--tag", t)]
        code, _, _ = cli(
            "table", str(flights / folder), "-o", str(dataset), *tag_args, "--workers", "1"
        )
        assert code == 0
    for name in ("findings", "attitude"):
        files = sorted((dataset / name).glob("*.parquet"))
        assert files and all(pq.ParquetFile(f).metadata.num_row_groups > 1 for f in files)
    assert not list(dataset.rglob(".partial-*"))
    assert questions(dataset) == questions(fleet["dataset"])
    for table in ("commands", "attitude", "findings", "diagnostics"):

        def key(r: dict[str, Any]) -> tuple[str, str]:
            return (r["content_hash"], json.dumps(r, sort_keys=True, default=str))

        assert sorted(rows(dataset, table), key=key) == sorted(
            rows(fleet["dataset"], table), key=key
        )


def test_collected_tables_join_their_row_groups() -> None:
    kept = CollectedTables()
    kept.write("t", pa.table({"a": [1, 2]}))
    kept.write("t", pa.table({"a": [3]}))
    kept.write("u", pa.table({"a": [9]}))
    kept.discard("u")
    assert {n: t.to_pydict() for n, t in kept.tables().items()} == {"t": {"a": [1, 2, 3]}}


def test_a_cluster_failure_is_one_line_without_a_class_name() -> None:
    from analyzer.fleet.runner import cluster_error

    class Scheduler:
        address = "tcp://127.0.0.1:1"

    class Client:
        scheduler = Scheduler()

    error = cluster_error(Client(), RuntimeError("the task lost its worker\nTraceback ..."))  # type: ignore[arg-type]
    assert str(error) == "the Dask cluster at tcp://127.0.0.1:1 failed: the task lost its worker"
