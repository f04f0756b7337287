"""Stored copies of command output (gzipped JSON): read, write, and compare one case."""

from __future__ import annotations

import difflib
import gzip
import hashlib
import json
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

import pytest

Cases = dict[str, dict[str, str]]  # case -> {"input_sha256": ..., "output": ...}


def entry(path: Path, output: str) -> dict[str, str]:
    """One case: its input's SHA-256 (a changed input is told apart) and the output."""
    return {"input_sha256": hashlib.sha256(path.read_bytes()).hexdigest(), "output": output}


def load(path: Path) -> Cases:
    data: Cases = json.loads(gzip.decompress(path.read_bytes()))
    return data


def save(path: Path, cases: Cases) -> None:
    text = json.dumps(cases, indent=0, sort_keys=True)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(gzip.compress(text.encode(), compresslevel=9, mtime=0))
    print(f"wrote {path} ({path.stat().st_size:,} bytes)")


def assert_same(case: str, want: dict[str, str], got: dict[str, str], command: str) -> None:
    """The same input, and byte for byte the same output (else the first lines that differ)."""
    assert got["input_sha256"] == want["input_sha256"], f"{case}: the input file changed"
    if got["output"] != want["output"]:
        diff = difflib.unified_diff(
            want["output"].splitlines(), got["output"].splitlines(), "stored", "now", lineterm=""
        )
        pytest.fail(f"{case}: {command} differs\n" + "\n".join(list(diff)[:40]))


def store_from_command_line(
    path: Path, outputs: Callable[[Path], Cases], usage: str | None
) -> None:
    """``python tests/test_X_equality.py --store``: the outputs of today's code, made in a
    temporary folder, become the stored copy (only on purpose, with the reason committed)."""
    if sys.argv[1:] != ["--store"]:
        raise SystemExit(usage)
    with tempfile.TemporaryDirectory() as folder:
        save(path, outputs(Path(folder)))
