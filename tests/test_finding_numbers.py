"""A finding's numbers agree with each other: its words, its JSON fields and the text
report's bracket say the same angles, errors and times (one set of numbers)."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest

from tests.analysis_corpus import write_corpus
from tests.fleet_flights import cli_output as cli

NUMBER = r"(-?\d+\.\d)"


@pytest.fixture(scope="module")
def corpus(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    made = write_corpus(tmp_path_factory.mktemp("corpus"))
    return {k: v for k, v in made.items() if k.endswith((".log", ".pcap"))}


@pytest.fixture(scope="module")
def findings(corpus: dict[str, Path]) -> list[dict[str, Any]]:
    found = []
    for path in corpus.values():
        found += [json.loads(line) for line in cli("analyze", str(path), "--json").splitlines()]
    return [f for f in found if f["check"] == "target"]


def one(value: float) -> str:
    return f"{value:.1f}"


def test_the_corpus_has_targets_of_every_kind(findings: list[dict[str, Any]]) -> None:
    details = " ".join(f["detail"] for f in findings)
    for words in ("never moved", "reached", "not at", "deg from the target"):
        assert words in details, words


def test_the_words_say_the_angles_the_fields_carry(findings: list[dict[str, Any]]) -> None:
    checked = 0
    for f in findings:
        if "final_deg" not in f:
            continue  # two axes (forward): each says its own angles
        detail, final = f["detail"], f["final_deg"]
        moved = re.search(rf"never moved \(from {NUMBER} to {NUMBER}, {NUMBER} deg from", detail)
        if moved:
            start, end, off = moved.groups()
            assert start == one(f["start_deg"]) and end == one(final), f
            assert off == one(abs(f["error_deg"])), f
            checked += 1
        for at, off in re.findall(rf"(?:at|to) {NUMBER}, {NUMBER} deg from the target", detail):
            assert at == one(final) and off == one(abs(f["error_deg"])), f
            checked += 1
        if f["axis"] == "pitch":  # the error is the target less the final angle
            assert f["error_deg"] == pytest.approx(f["target_deg"] - final, abs=0.002), f
    assert checked >= 5


def test_the_text_report_shows_the_json_numbers(corpus: dict[str, Path]) -> None:
    path = str(corpus["flight-candump.log"])
    by_time = {f["time"]: f for f in map(json.loads, cli("analyze", path, "--json").splitlines())}
    text = cli("analyze", path)
    never = next(line for line in text.splitlines() if "never moved (from" in line)
    start, end = re.search(rf"never moved \(from {NUMBER} to {NUMBER}", never).groups()  # type: ignore[union-attr]
    bracket = dict(re.findall(r"(start|final|error) (-?\d+\.\d\d) deg", never))
    (f,) = [
        f
        for f in by_time.values()
        if f["check"] == "target" and f["detail"] in never and "final_deg" in f
    ]
    assert bracket == {
        "start": f"{f['start_deg']:.2f}",
        "final": f"{f['final_deg']:.2f}",
        "error": f"{f['error_deg']:.2f}",
    }
    assert start == one(f["start_deg"]) and end == one(f["final_deg"])
