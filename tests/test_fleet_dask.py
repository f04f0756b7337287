"""`table --dask` and `fleet --dask` on a real Dask cluster: a scheduler and two workers as
separate processes on 127.0.0.1, started and stopped by the test."""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import socket
import subprocess
import sys
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from analyzer.fleet.columns import TABLES
from analyzer.fleet.dataset import Dataset
from tests.fleet_flights import cli, make_fleet

distributed = pytest.importorskip("distributed")  # pip install '.[cluster]' (the test extra has it)

ROOT = Path(__file__).resolve().parent.parent
START_TIMEOUT_S = 60
STOP_TIMEOUT_S = 15
TAGS = ("--tag", "gimbal=A", "--tag", "firmware=1.2")


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port: int = sock.getsockname()[1]
        return port


def dask_command() -> list[str]:
    found = shutil.which("dask", path=os.path.dirname(sys.executable)) or shutil.which("dask")
    return [found] if found else [sys.executable, "-m", "dask"]


def private_view(folder: Path) -> list[str]:
    """A command prefix that gives a process its own empty ``folder`` (a tmpfs in a mount
    namespace of its own): a worker that cannot reach what this process sees there.
    [] when this system has no user namespaces."""
    unshare = shutil.which("unshare")
    if unshare is None:
        return []
    probe = subprocess.run(
        [unshare, "-r", "-m", "sh", "-c", f"mount -t tmpfs none '{folder}'"],
        capture_output=True,
        timeout=STOP_TIMEOUT_S,
    )
    if probe.returncode != 0:
        return []
    return [unshare, "-r", "-m", "sh", "-c", f"mount -t tmpfs none '{folder}' && exec \"$@\"", "-"]


@contextlib.contextmanager
def cluster(tmp_path: Path, private: Path) -> Iterator[tuple[str, list[str], bool]]:
    """A scheduler and two single-threaded workers (no nanny: the worker is the process);
    the workers do not see what is in ``private`` (when the system allows)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    workers = [f"tcp://127.0.0.1:{free_port()}" for _ in range(2)]
    hidden = private_view(private)
    commands = [
        [*dask_command(), "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"]
    ]
    for worker in workers:
        commands.append(
            [
                *hidden, *dask_command(), "worker", address, "--host", "127.0.0.1",
                "--worker-port", worker.rsplit(":", 1)[1], "--nthreads", "1", "--no-nanny",
                "--no-dashboard", "--local-directory", str(tmp_path / "dask-worker"),
            ]
        )  # fmt: skip
    processes: list[subprocess.Popen[bytes]] = []
    logs = []
    try:
        for n, command in enumerate(commands):
            log = open(tmp_path / f"dask-{n}.log", "wb")  # noqa: SIM115 (closed below)
            logs.append(log)
            processes.append(
                subprocess.Popen(
                    command, env=env, stdout=log, stderr=subprocess.STDOUT, cwd=tmp_path
                )
            )
            if n == 0:
                wait_for_port(port, processes[0])
        with distributed.Client(address, timeout=START_TIMEOUT_S) as client:
            client.wait_for_workers(2, timeout=START_TIMEOUT_S)
            assert sorted(client.scheduler_info()["workers"]) == sorted(workers)
        yield address, workers, bool(hidden)
    finally:
        # The workers first (they close their links to each other while the scheduler
        # is still there), then the scheduler.
        stop(processes[1:])
        stop(processes[:1])
        for log in logs:
            log.close()


def stop(processes: list[subprocess.Popen[bytes]]) -> None:
    for process in processes:
        process.terminate()
    for process in processes:
        try:
            process.wait(STOP_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(STOP_TIMEOUT_S)


def wait_for_port(port: int, process: subprocess.Popen[bytes]) -> None:
    deadline = time.monotonic() + START_TIMEOUT_S
    while time.monotonic() < deadline:
        assert process.poll() is None, "the scheduler exited"
        with socket.socket() as sock:
            if sock.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.1)
    pytest.fail(f"the scheduler did not listen on port {port} within {START_TIMEOUT_S} s")


def dataset_tables(dataset: Path) -> dict[str, pa.Table]:
    """Every table of a dataset, rows in a fixed order."""
    out = {}
    for name in TABLES:
        files = sorted((dataset / name).glob("*.parquet"))
        if files:
            table = pa.concat_tables([pq.read_table(f) for f in files])
            keys = [(c, "ascending") for c in ("content_hash", "time") if c in table.column_names]
            out[name] = table.sort_by(keys)
    return out


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    """The fleet, its dataset made locally, and a cluster whose workers see all of it but
    the folder ``private``."""
    root = tmp_path_factory.mktemp("dask")
    make_fleet(root)
    flights = str(root / "flights")
    local = root / "local"
    code, _, err = cli("table", flights, "-o", str(local), *TAGS, "--workers", "1")
    assert code == 0, err
    (root / "private").mkdir()
    with cluster(root, root / "private") as (address, workers, hidden):
        yield {
            "root": root, "flights": flights, "local": local, "address": address,
            "workers": workers, "hidden": hidden,
        }  # fmt: skip


class ClientWrites:
    """Records which tables this process writes into a dataset (the rest were the workers')."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        self.tables: Counter[str] = Counter()
        original = Dataset._write_one

        def write_one(target: Path, table: pa.Table) -> None:
            self.tables[target.parent.name] += 1
            original(target, table)

        monkeypatch.setattr(Dataset, "_write_one", staticmethod(write_one))


def ran_on(out: str) -> dict[str, int]:
    (ran,) = [line for line in out.splitlines() if line.startswith("tasks ran on: ")]
    places = [part.rsplit(" (", 1) for part in ran.removeprefix("tasks ran on: ").split(", ")]
    return {place: int(n.rstrip(")")) for place, n in places}


@pytest.mark.slow
def test_table_on_a_dask_cluster_gives_the_local_dataset_written_by_the_workers(
    fleet: dict[str, Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    remote = fleet["root"] / "remote"
    written = ClientWrites(monkeypatch)
    code, out, err = cli(
        "table", fleet["flights"], "-o", str(remote), *TAGS, "--dask", fleet["address"]
    )
    assert code == 0, err
    # Every task ran on one of the two workers, none in this process.
    places = ran_on(out)
    assert set(places) <= set(fleet["workers"]) and sum(places.values()) == 6
    assert "6 input(s), 5 added" in out and "1 with errors" in out
    # This process wrote the recordings rows only; the other tables are the workers' files.
    assert dict(written.tables) == {"recordings": 6}
    assert "written by: the workers (recordings rows: here)" in out
    mine, theirs = dataset_tables(fleet["local"]), dataset_tables(remote)
    assert set(mine) == set(theirs) and len(theirs["attitude"]) > 0
    for name in mine:
        assert mine[name].equals(theirs[name]), name


@pytest.mark.slow
def test_client_writes_for_a_folder_the_workers_cannot_reach(
    fleet: dict[str, Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    if not fleet["hidden"]:
        pytest.skip("no user namespaces here: the workers see every folder")
    target = fleet["root"] / "private" / "fleet"
    code, out, err = cli(
        "table", fleet["flights"], "-o", str(target), *TAGS, "--dask", fleet["address"]
    )
    assert code == 2 and out == ""
    assert err.startswith(f"gimbal-analyzer table: error: the Dask workers cannot write {target}")
    assert "--client-writes" in err and err.count("\n") == 1
    assert not target.exists()  # what the check made is gone
    written = ClientWrites(monkeypatch)
    code, out, err = cli(
        "table", fleet["flights"], "-o", str(target), *TAGS, "--dask", fleet["address"],
        "--client-writes",
    )  # fmt: skip
    assert code == 0, err
    assert set(ran_on(out)) <= set(fleet["workers"]) and "written by: this process" in out
    assert written.tables["recordings"] == 6 and written.tables["attitude"] == 4
    mine, theirs = dataset_tables(fleet["local"]), dataset_tables(target)
    assert set(mine) == set(theirs)
    for name in mine:
        assert mine[name].equals(theirs[name]), name


@pytest.mark.slow
def test_fleet_questions_are_aggregated_on_the_workers(fleet: dict[str, Any]) -> None:
    local, address = str(fleet["local"]), fleet["address"]
    code, here, _ = cli("fleet", local, "--json")
    assert code == 0 and len(here.splitlines()) > 10
    with (
        distributed.Client(address, timeout=START_TIMEOUT_S) as watcher,
        distributed.get_task_stream(client=watcher) as stream,
    ):
        code, on_cluster, err = cli("fleet", local, "--json", "--dask", address)
    assert code == 0, err
    # The same answers, to the last digit (medians too).
    assert [json.loads(x) for x in on_cluster.splitlines()] == [
        json.loads(x) for x in here.splitlines()
    ]
    # Only the aggregated rows came back: one per group of each question (the worst
    # flights: the candidates, fewer than its limit here).
    questions = {json.loads(x)["question"] for x in here.splitlines()}
    assert f"{len(questions)} question(s) aggregated on the workers of {address}; " in err
    assert f"; {len(here.splitlines())} aggregated rows came back" in err
    # The reading, joining, shuffling and aggregating ran on the two workers.
    kinds: dict[str, set[str]] = {}
    for task in stream.data:
        key = task["key"][0] if isinstance(task["key"], tuple) else task["key"]
        kinds.setdefault(str(key).rsplit("-", 1)[0], set()).add(task["worker"])
    for kind in ("read_part", "_groupby_apply_funcs", "shuffle-transfer", "customreduction-tree"):
        assert kind in kinds and kinds[kind] <= set(fleet["workers"]), kind
    assert set().union(*kinds.values()) == set(fleet["workers"])


@pytest.mark.slow
def test_the_fleet_report_from_a_cluster_is_the_local_one(
    fleet: dict[str, Any], tmp_path: Path
) -> None:
    local, address = str(fleet["local"]), fleet["address"]
    pages = {}
    for name, extra in (("here", ()), ("there", ("--dask", address))):
        page = tmp_path / f"{name}.html"
        code, _, err = cli("fleet", local, "--html", str(page), *extra)
        assert code == 0, err
        pages[name] = re.sub(r"made [^.]+\.\d+Z", "made (time)", page.read_text(encoding="utf-8"))
    assert pages["there"] == pages["here"] and "b-cut.pcap" in pages["here"]


@pytest.mark.slow
def test_fleet_sql_on_a_cluster_reads_the_named_columns_there(fleet: dict[str, Any]) -> None:
    local, address = str(fleet["local"]), fleet["address"]
    sql = "SELECT f.verdict, count(*) AS n FROM findings f GROUP BY 1 ORDER BY 1"
    code, on_cluster, err = cli("fleet", local, "--sql", sql, "--csv", "--dask", address)
    assert code == 0, err
    code, here, _ = cli("fleet", local, "--sql", sql, "--csv")
    assert on_cluster == here and here.startswith("verdict,n\ndegraded,")
    assert "\nlost," in here and "\nnot_obeyed," in here  # health words beside verdicts
    total = sum(int(line.split(",")[1]) for line in here.splitlines()[1:])
    assert err == (
        f"fleet: the workers of {address} read findings (verdict); {total:,} rows came back "
        "and the query ran here\n"
    )


@pytest.mark.slow
def test_a_cluster_without_the_package_is_one_line(fleet: dict[str, Any], tmp_path: Path) -> None:
    """A scheduler started where gimbal-analyzer is not installed cannot take its tasks."""
    port = free_port()
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    found = subprocess.run(
        [sys.executable, "-c", "import analyzer"], env=env, cwd=tmp_path, capture_output=True
    )
    if found.returncode == 0:
        pytest.skip("gimbal-analyzer is installed in this environment: no bare scheduler")
    command = [*dask_command(), "scheduler", "--host", "127.0.0.1", "--port", str(port)]
    with open(tmp_path / "bare.log", "wb") as log:
        bare = subprocess.Popen(
            [*command, "--no-dashboard"], env=env, stdout=log, stderr=log, cwd=tmp_path
        )
        try:
            wait_for_port(port, bare)
            address = f"tcp://127.0.0.1:{port}"
            code, _, err = cli("fleet", str(fleet["local"]), "--dask", address)
        finally:
            stop([bare])
    assert code == 1 and err == (
        f"gimbal-analyzer fleet: error: the Dask cluster at {address} cannot run "
        "gimbal-analyzer's tasks: install the package where its scheduler and workers run "
        "(pip install 'gimbal-analyzer[cluster]')\n"
    )


def test_a_wrong_scheduler_address_leaves_nothing_behind(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr("analyzer.fleet.runner.CONNECT_TIMEOUT_S", 1)
    flight = tmp_path / "f.log"
    flight.write_text("(1700000000.000000) can0 00000000#00\n", encoding="utf-8")
    target = tmp_path / "fleet"
    nobody = f"tcp://127.0.0.1:{free_port()}"
    code, out, err = cli("table", str(flight), "-o", str(target), "--dask", nobody)
    assert code == 2 and out == ""
    assert err.startswith(
        f"gimbal-analyzer table: error: cannot reach the Dask scheduler at {nobody}: "
    )
    assert not target.exists()
