"""Memory stays flat: a 2M-frame log needs no more than a tenth of it, and 150 MB at most.

The columnar path reads a block at a time and nothing keeps a block's frames or events
once its batch is delivered. Each command that reads through it runs on a dense log of
200,000 and of 2,000,000 frames (candump text, and the same frames as BLF) in a fresh
process, and its peak memory (VmHWM) is compared.
"""

from __future__ import annotations

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

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")


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
}


@pytest.mark.parametrize(
    ("kind", "command"),
    [*(("log", c) for c in sorted(COMMANDS)), ("blf", "decode --summary"), ("blf", "analyze")],
)
def test_memory_stays_flat_on_a_2m_frame_file(
    tmp_path: Path, logs: dict[str, Path], command: str, kind: str
) -> None:
    small = peak_mb(tmp_path, *COMMANDS[command], str(logs[f"{kind}-200000"]))
    large = peak_mb(tmp_path, *COMMANDS[command], str(logs[f"{kind}-2000000"]))
    assert large <= LIMIT_MB, (small, large)
    assert large <= small + FLAT_MB, (small, large)
