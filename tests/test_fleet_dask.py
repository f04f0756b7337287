"""`table --dask` and `fleet --dask` on a real Dask cluster: a scheduler and two workers as
separate processes on 127.0.0.1, started and stopped by the test."""

from __future__ import annotations

import contextlib
import io
import json
import os
import shutil
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from analyzer.cli import main
from analyzer.fleet.columns import TABLES
from tests.fleet_flights import make_fleet

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


@contextlib.contextmanager
def cluster(tmp_path: Path) -> Iterator[tuple[str, list[str]]]:
    """A scheduler and two single-threaded workers (no nanny: the worker is the process)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    workers = [f"tcp://127.0.0.1:{free_port()}" for _ in range(2)]
    commands = [
        [*dask_command(), "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"]
    ]
    for worker in workers:
        commands.append(
            [
                *dask_command(), "worker", address, "--host", "127.0.0.1",
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
        yield address, workers
    finally:
        for process in reversed(processes):
            process.terminate()
        for process in processes:
            try:
                process.wait(STOP_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(STOP_TIMEOUT_S)
        for log in logs:
            log.close()


def wait_for_port(port: int, process: subprocess.Popen[bytes]) -> None:
    deadline = time.monotonic() + START_TIMEOUT_S
    while time.monotonic() < deadline:
        assert process.poll() is None, "the scheduler exited"
        with socket.socket() as sock:
            if sock.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.1)
    pytest.fail(f"the scheduler did not listen on port {port} within {START_TIMEOUT_S} s")


def cli(*args: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(list(args))
    return code, out.getvalue(), err.getvalue()


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


def test_table_on_a_dask_cluster_gives_the_local_dataset(tmp_path: Path) -> None:
    make_fleet(tmp_path)
    flights = str(tmp_path / "flights")
    local, remote = tmp_path / "local", tmp_path / "remote"
    code, out, err = cli("table", flights, "-o", str(local), *TAGS, "--workers", "1")
    assert code == 0, err
    with cluster(tmp_path) as (address, workers):
        code, out, err = cli("table", flights, "-o", str(remote), *TAGS, "--dask", address)
        assert code == 0, err
        # Every task ran on one of the two workers, none in this process.
        (ran,) = [line for line in out.splitlines() if line.startswith("tasks ran on: ")]
        places = dict(
            part.rsplit(" (", 1) for part in ran.removeprefix("tasks ran on: ").split(", ")
        )
        assert set(places) <= set(workers) and sum(int(n.rstrip(")")) for n in places.values()) == 6
        assert "6 input(s), 5 added" in out and "1 with errors" in out
        # The questions, with the tables read by dask.dataframe on the workers.
        code, on_cluster, err = cli("fleet", str(remote), "--json", "--dask", address)
        assert code == 0, err
        sql = "SELECT f.verdict, count(*) AS n FROM findings f GROUP BY 1 ORDER BY 1"
        code, sql_on_cluster, err = cli(
            "fleet", str(remote), "--sql", sql, "--csv", "--dask", address
        )
        assert code == 0, err
    mine, theirs = dataset_tables(local), dataset_tables(remote)
    assert set(mine) == set(theirs)
    for name in mine:
        assert mine[name].equals(theirs[name]), name
    code, here, _ = cli("fleet", str(local), "--json")
    assert [json.loads(x) for x in on_cluster.splitlines()] == [
        json.loads(x) for x in here.splitlines()
    ]
    assert len(here.splitlines()) > 10
    code, sql_here, _ = cli("fleet", str(local), "--sql", sql, "--csv")
    assert sql_on_cluster == sql_here and sql_here.startswith("verdict,n\nnot_obeyed,")
