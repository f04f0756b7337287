"""Memory stays flat: a 2M-frame log needs no more than a tenth of it, and 150 MB at most.

The columnar path reads a block at a time and nothing keeps a block's frames or events
once its batch is delivered; ``table`` keeps at most a Parquet row group of each table.
Each command that reads through it runs on a dense log of 200,000 and of 2,000,000
frames (candump text, and the same frames as BLF) in a fresh process, and its peak
memory (VmHWM) is compared. ``table`` imports neither pandas (pyarrow would, for
``pa.array``, where pandas is installed: tens of MB) nor what it does not use.
"""

from __future__ import annotations

import importlib.util
import itertools
import subprocess
import sys
from pathlib import Path

import pytest

from analyzer.inputs.candump.reader import CandumpReader
from analyzer.protocol.frame_columns import FrameColumns
from benchmarks.decode_speed import write_log
from tests.blf_files import blf_of_columns

LIMIT_MB = 150
FLAT_MB = 12  # what ten times the frames may add (numbers of a few counters, not frames)

PEAK = """
import sys
from analyzer.cli import main
code = main(sys.argv[1:])
sys.stdout.flush()
peak = [l for l in open("/proc/self/status") if l.startswith("VmHWM:")]
print(int(peak[0].split()[1]) // 1024, file=sys.stderr)
sys.exit(code)
"""

pytestmark = [
    pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc"),
    pytest.mark.slow,  # seconds a command on 2M frames, and the logs to write first
]
ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def logs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("memory")
    out: dict[str, Path] = {}
    for frames in (200_000, 2_000_000):
        text = folder / f"dense-{frames}.log"
        write_log(text, frames, "dense")
        with CandumpReader(str(text)) as reader:
            columns = [i for batch in reader.batches(1 << 20) for i in batch]
        blf = folder / f"dense-{frames}.blf"
        blf.write_bytes(blf_of_columns(_joined(columns)))
        out[f"log-{frames}"], out[f"blf-{frames}"] = text, blf
    half = out["log-1000000"] = folder / "dense-1000000.log"  # the first half of 2M
    with (
        out["log-2000000"].open(encoding="utf-8") as whole,
        half.open("w", encoding="utf-8") as first,
    ):
        first.writelines(itertools.islice(whole, 1_000_000))
    return out


def _joined(items: list[object]) -> FrameColumns:
    import numpy as np

    blocks = [i for i in items if isinstance(i, FrameColumns)]
    assert all(b.channels == blocks[0].channels for b in blocks)
    return FrameColumns(
        *(
            np.concatenate([getattr(b, name) for b in blocks])
            for name in ("time", "can_id", "extended", "length", "data", "channel")
        ),
        blocks[0].channels,
        np.concatenate([b.direction for b in blocks]),
    )


def peak_mb(tmp_path: Path, *argv: str) -> int:
    proc = subprocess.run(
        [sys.executable, "-c", PEAK, *argv],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        check=True,
        cwd=tmp_path,
        encoding="utf-8",
    )
    return int(proc.stderr.split()[-1])


COMMANDS = {
    "decode --summary": ["decode", "--summary"],
    "decode --json": ["decode", "--json"],
    "analyze": ["analyze"],
    "convert": ["convert", "--force", "-o", "out.mcap"],
    "table": ["table", "-o", "fleet", "--workers", "1", "-q"],
}
# The frames a command is first measured on, when not 200,000. `table` holds up to a
# Parquet row group (16,384 rows) of each table, and less until then: on the dense log
# the attitude table fills its first row group after about 800,000 frames.
SMALL = {"table": 1_000_000}


@pytest.mark.parametrize(
    ("kind", "command"),
    [*(("log", c) for c in sorted(COMMANDS)), ("blf", "decode --summary"), ("blf", "analyze")],
)
def test_memory_stays_flat_on_a_2m_frame_file(
    tmp_path: Path, logs: dict[str, Path], command: str, kind: str
) -> None:
    small = peak_mb(
        tmp_path, *COMMANDS[command], str(logs[f"{kind}-{SMALL.get(command, 200_000)}"])
    )
    large = peak_mb(tmp_path, *COMMANDS[command], str(logs[f"{kind}-2000000"]))
    assert large <= LIMIT_MB, (small, large)
    assert large <= small + FLAT_MB, (small, large)


LOADED = """
import sys
from analyzer.cli import main
code = main(sys.argv[2:])
print(" ".join(m for m in sys.argv[1].split(",") if m in sys.modules))
sys.exit(code)
"""


@pytest.mark.skipif(importlib.util.find_spec("pandas") is None, reason="pandas not installed")
def test_table_never_imports_pandas_even_where_it_is_installed(tmp_path: Path) -> None:
    unused = ("pandas", "duckdb", "pyarrow.compute", "pyarrow.dataset")
    sample = ROOT / "samples" / "flight-candump.log"
    # a new dataset, then one that holds the input (its tags read), then --retag
    for run, more in ((0, []), (1, []), (2, ["--retag"])):
        argv = ["table", str(sample), "-o", "fleet", "--tag", f"run={run}", *more]
        proc = subprocess.run(
            [sys.executable, "-c", LOADED, ",".join(unused), *argv],
            capture_output=True, text=True, check=True, cwd=tmp_path, encoding="utf-8",
        )  # fmt: skip
        assert proc.stdout.splitlines()[-1] == "", proc.stdout
    assert "retagged" in proc.stdout and "1 skipped" in proc.stdout
