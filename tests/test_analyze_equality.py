"""``analyze --json`` gives, byte for byte, the findings it gave before the analysis streamed.

``tests/data/analyze_json.json.gz`` holds the findings of every input of
``tests/analysis_corpus.py`` (the samples, the fault logs, the fleet's flights, simulator
sessions with faults and disobedience, a slice of the dense bus mix), and the SHA-256 of
each input (so that a change of the input is told apart from a change of the analysis).
Regenerate it only when a verdict is meant to change, and say which in the commit:

    python tests/test_analyze_equality.py --store
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
from tests.analysis_corpus import write_corpus  # noqa: E402
from tests.stored_copy import (  # noqa: E402
    assert_same,
    entry,
    load,
    store_from_command_line,
)

STORED = ROOT / "tests" / "data" / "analyze_json.json.gz"
OPTIONS: dict[str, tuple[str, ...]] = {
    "sim-disobedient.log": ("--tolerance", "2", "--time-allowed", "3"),
}


def analyze_json(path: Path, options: tuple[str, ...]) -> str:
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        assert main(["analyze", str(path), "--json", *options]) == 0
    return out.getvalue()


def outputs(folder: Path) -> dict[str, dict[str, str]]:
    """Each input's hash and ``analyze --json`` output (with and without its options)."""
    found = {}
    for name, path in write_corpus(folder).items():
        runs = [()] + ([OPTIONS[name]] if name in OPTIONS else [])
        for options in runs:
            found[" ".join([name, *options])] = entry(path, analyze_json(path, options))
    return found


def stored() -> dict[str, dict[str, str]]:
    return load(STORED)


@pytest.fixture(scope="module")
def current(tmp_path_factory: pytest.TempPathFactory) -> dict[str, dict[str, str]]:
    return outputs(tmp_path_factory.mktemp("corpus"))


def test_every_input_of_the_corpus_is_stored(current: dict[str, dict[str, str]]) -> None:
    assert sorted(current) == sorted(stored())


@pytest.mark.parametrize("case", sorted(stored()) if STORED.exists() else [])
def test_analyze_json_is_byte_for_byte_the_stored_copy(
    case: str, current: dict[str, dict[str, str]]
) -> None:
    assert_same(case, stored()[case], current[case], "analyze --json")


def test_the_corpus_has_findings_of_every_verdict(current: dict[str, dict[str, str]]) -> None:
    findings = [
        json.loads(line) for case in current.values() for line in case["output"].splitlines()
    ]
    commands = {f["verdict"] for f in findings if f["command"] != "feedback"}
    assert commands == {"obeyed", "partial", "not_obeyed", "unknown"}
    health = {f["verdict"] for f in findings if f["command"] == "feedback"}
    assert health == {"healthy", "degraded", "lost"}
    assert {f["check"] for f in findings} >= {
        "target", "rate", "stop", "repeat", "tracking", "feedback", "feedback_gap", "limit"
    }  # fmt: skip


if __name__ == "__main__":
    store_from_command_line(STORED, outputs, __doc__)
