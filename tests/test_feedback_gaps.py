"""Lost feedback is counted from the expected period, the same way by every command.

The gimbal answers every 0.5 s. A silence of 1.5 periods or more has lost at least one
message, round(silence / period) - 1 of them: the message after a loss a fraction of a
millisecond early or late changes nothing, in ``analyze``, ``decode --summary``,
``info``, ``table`` (and the report, which shows ``analyze``'s findings).
"""

from __future__ import annotations

import json
import random
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from analyzer.feedback_track import GAP_PERIODS, lost_messages
from analyzer.protocol.feedback import encode_attitude, segments
from tests.fleet_flights import cli_output as cli

T0 = 1_700_000_000.0
PERIOD = 0.5
LOST = {10: 1, 20: 1, 30: 2, 41: 1, 52: 3}  # message index -> messages lost before it
GAPS, MESSAGES_LOST = len(LOST), sum(LOST.values())


def test_lost_messages_are_counted_in_periods() -> None:
    assert [lost_messages(s) for s in (0.5, 0.7499, 0.75, 0.9998, 1.0, 1.0002)] == [
        0, 0, 1, 1, 1, 1
    ]  # fmt: skip
    assert [lost_messages(s) for s in (1.4998, 1.5002, 2.0, 3.5)] == [2, 2, 3, 6]
    assert lost_messages(float("nan")) == 0 and lost_messages(-1.0) == 0
    assert lost_messages(0.1, period_s=0.025) == 3  # any period
    assert GAP_PERIODS == 1.5


def feedback_times(shift: float, seed: int) -> list[float]:
    """Messages every 0.5 s with the losses of LOST; each message after a loss ``shift``
    seconds off, the others jittered by up to 0.2 ms either way."""
    rng = random.Random(seed)
    times, slot = [], 0
    for i in range(70):
        slot += 1 + LOST.get(i, 0)
        jitter = shift if i in LOST else rng.uniform(-0.0002, 0.0002)
        times.append(T0 + slot * PERIOD + jitter)
    return times


def write_log(path: Path, times: list[float]) -> Path:
    lines = []
    for n, t in enumerate(times):
        message = encode_attitude(pitch_deg=-10.0 + n * 0.01, yaw_deg=5.0, motor_yaw_deg=5.0)
        for part in segments(message):
            lines.append(f"({t:.6f}) can0 030F0001#{part.hex().upper()}")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def logs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("gaps")
    return {
        name: write_log(folder / f"{name}.log", feedback_times(shift, seed))
        for name, shift, seed in (("late", 0.0002, 1), ("early", -0.0002, 2), ("exact", 0.0, 3))
    }


def analyze_counts(path: Path) -> tuple[int, int, int, int]:
    found = [json.loads(line) for line in cli("analyze", str(path), "--json").splitlines()]
    gaps = [f for f in found if f["check"] == "feedback_gap"]
    (window,) = [f for f in found if f["check"] == "feedback"]
    assert all(f["verdict"] == "lost" for f in gaps)
    return len(gaps), sum(f["lost_messages"] for f in gaps), window["gaps"], window["lost_messages"]


@pytest.mark.parametrize("name", ["late", "early", "exact"])
def test_every_command_counts_the_same_gaps_whatever_the_jitter(
    name: str, logs: dict[str, Path], tmp_path: Path
) -> None:
    path = logs[name]
    assert analyze_counts(path) == (GAPS, MESSAGES_LOST, GAPS, MESSAGES_LOST)
    summary = json.loads(cli("decode", str(path), "--summary", "--json"))
    (track,) = summary["feedback"].values()
    assert (track["gaps_over_threshold"], track["lost_messages"]) == (GAPS, MESSAGES_LOST)
    text = cli("decode", str(path), "--summary")
    assert f"{GAPS} gaps, {MESSAGES_LOST} messages lost" in text
    recording = tmp_path / "flight.mcap"
    cli("convert", str(path), "-o", str(recording), "-q")
    info = json.loads(cli("info", str(recording), "--json"))
    (track,) = info["figures"]["feedback"].values()
    assert (track["gaps_over_threshold"], track["lost_messages"]) == (GAPS, MESSAGES_LOST)
    assert f"{GAPS} gaps, {MESSAGES_LOST} messages lost" in cli("info", str(recording))
    found = cli("analyze", str(recording), "--json").splitlines()
    assert sum(json.loads(f)["check"] == "feedback_gap" for f in found) == GAPS


def test_the_fleet_table_counts_them_too(logs: dict[str, Path], tmp_path: Path) -> None:
    dataset = tmp_path / "fleet"
    cli("table", *(str(p) for p in logs.values()), "-o", str(dataset), "--workers", "1", "-q")
    rows = pq.read_table(dataset / "recordings").to_pylist()
    assert [r["gaps"] for r in rows] == [GAPS] * 3


def test_the_text_report_speaks_of_health_not_obedience(logs: dict[str, Path]) -> None:
    text = cli("analyze", str(logs["late"]))
    assert "feedback_gap LOST        feedback lost: 2 messages missing" in text
    assert "NOT OBEYED" not in text and "feedback     obeyed" not in text
    assert "verdicts: 0 obeyed, 0 partial, 0 not obeyed, 0 unknown" in text
    assert f"feedback: 1 of 1 minute degraded; {GAPS} gaps, {MESSAGES_LOST} messages lost" in text
