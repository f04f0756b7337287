"""A fleet question counts commands as commands: feedback damage is health, not disobedience.

Twelve flights, each with one pitch target the gimbal ignores and feedback damaged on
the bus: "how many commands were not obeyed" is 12, however many CRC errors there were.
"""

from __future__ import annotations

import json
from pathlib import Path

from analyzer.sim.behaviour import Behaviour
from analyzer.sim.engine import SimConfig
from analyzer.sim.faults import FaultConfig
from analyzer.sim.ground import Step
from analyzer.sim.offline import run_offline
from tests.analysis_corpus import candump_text
from tests.fleet_flights import cli_output

FLIGHTS = 12
SCRIPT = (Step(1.0, "specified_angle", {"pitch_deg": -45}),)


def test_twelve_ignored_pitches_are_twelve_commands_not_obeyed(tmp_path: Path) -> None:
    flights = tmp_path / "flights"
    flights.mkdir()
    for n in range(FLIGHTS):
        config = SimConfig(
            behaviour=Behaviour(ignore=frozenset({"specified_angle"})),
            faults=FaultConfig(corrupt=0.1, drop=0.02, seed=n),
        )
        frames, _ = run_offline(SCRIPT, 20.0, config, start=1_715_680_800.0 + 3600 * n)
        (flights / f"flight-{n:02}.log").write_text(candump_text(frames), encoding="utf-8")
    dataset = tmp_path / "dataset"
    cli_output("table", str(flights), "-o", str(dataset), "-q")
    sql = "SELECT verdict, count(*) AS n FROM findings GROUP BY 1 ORDER BY 1"
    answer = cli_output("fleet", str(dataset), "--sql", sql, "--json")
    counts = {row["verdict"]: row["n"] for row in map(json.loads, answer.splitlines())}
    assert counts["not_obeyed"] == FLIGHTS
    assert counts.get("degraded", 0) + counts.get("lost", 0) > FLIGHTS  # the damage is there
    columns = "SELECT sum(findings_not_obeyed) AS c, sum(crc_errors) AS crc FROM recordings"
    (row,) = map(
        json.loads, cli_output("fleet", str(dataset), "--sql", columns, "--json").splitlines()
    )
    assert row["c"] == FLIGHTS and row["crc"] > FLIGHTS
    # analyze says the same of each flight as the table
    found = [
        json.loads(line)
        for line in cli_output("analyze", str(flights / "flight-00.log"), "--json").splitlines()
    ]
    assert [f["verdict"] for f in found if f["command"] != "feedback"] == ["not_obeyed"]
