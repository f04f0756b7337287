"""Start-up is lazy: ``decode`` of a candump log loads what decoding it needs, nothing more.

Each case runs the command line in a fresh interpreter and looks at what it loaded:
no analysis, recording, report or video code, no heavy library, and numpy only for a
log dense with the protocol's frames (read as arrays). numpy's OpenBLAS starts no
threads of its own for it (``python -X importtime`` shows the rest).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from benchmarks.decode_speed import write_log

# Loaded by a command that does something else, never by decoding a candump log.
HEAVY = {
    "pyarrow",
    "duckdb",
    "cv2",
    "av",
    "mcap",
    "textual",
    "can",
    "lupa",
    "dask",
    "matplotlib",
    "analyzer.analysis",
    "analyzer.mcapio",
    "analyzer.report",
    "analyzer.fleet",
    "analyzer.video",
    "analyzer.inputs.python_can",
    "analyzer.inputs.pcap",
    "analyzer.protocol.framing",
}

PROBE = """
import io, json, os, sys
from contextlib import redirect_stdout
from analyzer.cli import main
with redirect_stdout(io.StringIO()):
    code = main(sys.argv[1:])
threads = len(os.listdir("/proc/self/task")) if os.path.isdir("/proc/self/task") else 1
print(json.dumps({"code": code, "modules": sorted(sys.modules), "threads": threads}))
"""


def loaded(*argv: str) -> dict[str, object]:
    env = {"PATH": "/usr/bin:/bin"}  # no OPENBLAS_NUM_THREADS from the caller
    proc = subprocess.run(
        [sys.executable, "-c", PROBE, *argv],
        capture_output=True,
        text=True,
        env=env,
        check=True,
        encoding="utf-8",
    )
    result: dict[str, object] = json.loads(proc.stdout.splitlines()[-1])
    return result


def heavy(modules: object) -> set[str]:
    assert isinstance(modules, list)
    return {m for m in modules if any(m == h or m.startswith(h + ".") for h in HEAVY)}


@pytest.mark.parametrize("mix", ["busy", "dense"])
def test_decode_loads_only_what_decoding_needs(tmp_path: Path, mix: str) -> None:
    path = tmp_path / f"{mix}.log"
    write_log(path, 20_000, mix)
    result = loaded("decode", "--summary", str(path))
    assert result["code"] == 0
    assert heavy(result["modules"]) == set()
    modules = result["modules"]
    assert isinstance(modules, list)
    # A busy drone bus (a few gimbal frames in a hundred) is scanned: no numpy at all.
    assert ("numpy" in modules) == (mix == "dense")
    if sys.platform.startswith("linux"):
        assert result["threads"] == 1  # OpenBLAS started no threads
