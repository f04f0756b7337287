"""``decode --json`` gives, byte for byte, what it gave before the decoder was made faster.

``tests/data/decode_json.json.gz`` holds the output of every sample and of the fault logs
of ``tests/fault_logs.py`` (with and without ``--raw``), as the decoder wrote it before
its hot paths were rewritten, and the SHA-256 of each input file (so that a change of
the input is told apart from a change of the decoder). Regenerate it only when the
output is meant to change:

    python tests/test_decode_equality.py --store
"""

from __future__ import annotations

import contextlib
import io
import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))

from analyzer.cli import main  # noqa: E402
from tests.fault_logs import CANDUMP_NAME, STREAM_NAME, write_fault_logs  # noqa: E402
from tests.stored_copy import (  # noqa: E402
    assert_same,
    entry,
    load,
    store_from_command_line,
)

STORED = ROOT / "tests" / "data" / "decode_json.json.gz"
SAMPLES = ROOT / "samples"
# (file, extra options): every sample, and the fault logs, which the test writes.
CASES = [
    ("flight-candump.log", ()),
    ("flight-candump.log", ("--raw",)),
    ("idu-tcp.pcap", ()),
    ("uart-dump.bin", ()),
    (CANDUMP_NAME, ()),
    (CANDUMP_NAME, ("--raw",)),
    (STREAM_NAME, ()),
]


def case_name(name: str, options: tuple[str, ...]) -> str:
    return " ".join([name, *options])


def decode_json(path: Path, options: tuple[str, ...]) -> str:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["decode", str(path), "--json", *options]) == 0
    return out.getvalue()


def input_path(name: str, folder: Path) -> Path:
    return SAMPLES / name if (SAMPLES / name).exists() else folder / name


def outputs(folder: Path) -> dict[str, dict[str, str]]:
    """Each case's input hash and ``decode --json`` output (fault logs written to folder)."""
    write_fault_logs(folder)
    found = {}
    for name, options in CASES:
        path = input_path(name, folder)
        found[case_name(name, options)] = entry(path, decode_json(path, options))
    return found


def stored() -> dict[str, dict[str, str]]:
    return load(STORED)


@pytest.fixture(scope="module")
def current(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict[str, str]]:
    return outputs(tmp_path_factory.mktemp("faults"))


@pytest.mark.parametrize("case", [case_name(n, o) for n, o in CASES])
def test_decode_json_is_byte_for_byte_the_stored_copy(
    case: str, current: dict[str, dict[str, str]]
) -> None:
    assert_same(case, stored()[case], current[case], "decode --json")


def test_the_fault_logs_hold_every_kind_of_trouble(current: dict[str, dict[str, str]]) -> None:
    events = [json.loads(line) for line in current[CANDUMP_NAME]["output"].splitlines()]
    kinds = {e["kind"] for e in events if e["topic"] == "/diagnostics"}
    assert kinds >= {
        "bad_frame",
        "bad_line",
        "bus_error",
        "crc_mismatch",
        "duplicate",
        "incomplete",
    }
    commands = [e for e in events if e["topic"] == "/gimbal/command"]
    warned = [w for e in commands for w in e["warnings"]]
    for words in ("out of range", "unknown value", "not zero", "unknown command", "CAN FD"):
        assert any(words in w for w in warned), words
    assert len({e["raw"] for e in commands}) > 0.9 * len(commands)  # hardly any repeats


if __name__ == "__main__":
    store_from_command_line(STORED, outputs, __doc__)
