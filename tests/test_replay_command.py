"""`gimbal-analyzer replay` and `compare` in real time, against the simulated gimbal.

The sample pilot flight (captured on CAN; its gimbal followed the stick 0.3 s late) is
replayed over TCP to a healthy simulated gimbal and to one acting 0.3 s late, each
replay a process of its own as a user runs it, all at once to keep the wall time
short; meanwhile a flight captured on TCP (the sample pcap) is replayed here to a CAN
bus (python-can's virtual bus: a simulated gimbal in this process). Then `compare`
finds the lag in the first and nothing in the second, as docs/howto/replay.md shows.
``test_replay_offline`` tests the logic in virtual time.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import statistics
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

import pytest

from analyzer import read
from analyzer.mcapio.read.reader import McapRecording
from analyzer.protocol.ids import ALTITUDE_ID, GPS_ID
from analyzer.protocol.types import TOPIC_COMMAND, TOPIC_DIAGNOSTICS, TOPIC_GIMBAL_ATTITUDE
from tests.platforms import posix_signals
from tests.readme_blocks import read_blocks
from tests.readme_examples import compare as compare_shown
from tests.replay_bench import read_span
from tests.test_check_command import Gimbal
from tests.test_replay_offline import cli
from tests.tool_runs import ToolRun, tool_process

ROOT = Path(__file__).resolve().parents[1]
HOWTO = ROOT / "docs" / "howto" / "replay.md"
FLIGHT = "samples/pilot-candump.log"


@dataclass
class Replay(ToolRun):
    """A replay as a process of its own, in ``folder`` (which holds a copy of samples/)."""

    gimbal: Gimbal = field(kw_only=True)
    folder: Path = field(kw_only=True)
    timeout_s: ClassVar[float] = 120.0

    def stop_gimbal(self) -> None:
        self.gimbal.close()

    def commands(self) -> list[str]:
        """What the gimbal received: the raw bytes of each command, in order."""
        return [e.fields["raw"] for e in self.gimbal.received if e.topic == TOPIC_COMMAND]


def start_replay(gimbal: Gimbal, folder: Path, *options: str) -> Replay:
    process = tool_process(["replay", FLIGHT, "--to", gimbal.to, *options], folder)
    return Replay(process, gimbal=gimbal, folder=folder)


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    here = tmp_path_factory.mktemp("replay")
    shutil.copytree(ROOT / "samples", here / "samples")
    return here


@pytest.fixture(scope="module")
def runs(folder: Path) -> Iterator[dict[str, Replay]]:
    started = {}
    try:
        for name, flags, output in (
            ("interrupted", (), "stopped.mcap"),
            ("healthy", (), "bench.mcap"),
            ("lag", ("--lag", "0.3"), "bench-lag.mcap"),
        ):
            end = () if name == "interrupted" else ("--end", "12")
            gimbal = Gimbal("tcp:127.0.0.1:0", *flags)
            started[name] = start_replay(gimbal, folder, *end, "-o", output)
        yield started
    finally:
        for run in started.values():
            run.abandon()


def flight_commands(end_s: float | None = 12.0) -> list[str]:
    span = read_span(ROOT / FLIGHT, 0.0, end_s)
    return [f.data.hex(" ").upper() for f in span.frames if f.is_command]


@pytest.mark.slow
@posix_signals
def test_ctrl_c_mid_replay_stops_and_centres_the_gimbal(runs: dict[str, Replay]) -> None:
    run = runs["interrupted"]
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:  # wait until the stick is turning the gimbal
        if any(e.fields.get("pan_speed_dps") for e in run.gimbal.received):
            break
        time.sleep(0.1)
    run.process.send_signal(signal.SIGINT)
    run.finish()
    assert run.code == 130, run.err
    assert "gimbal-analyzer replay: interrupted" in run.err
    *_, stop, centre = [e.fields for e in run.gimbal.received if e.topic == TOPIC_COMMAND]
    assert stop["name"] == "gimbal_control" and stop["pan_speed_dps"] == 0
    assert stop["tilt_speed_dps"] == 0 and centre["name"] == "forward"
    marks = [
        e.fields["detail"]
        for e in read(run.folder / "stopped.mcap")  # the recording is finished and marked
        if e.topic == TOPIC_DIAGNOSTICS and e.fields.get("state") == "replay_end"
    ]
    assert len(marks) == 1 and "stopped: interrupted" in marks[0]


@pytest.mark.slow
def test_a_flight_captured_on_tcp_replays_to_a_can_bus(folder: Path) -> None:
    pcap = folder / "samples" / "idu-tcp.pcap"
    gimbal = Gimbal(f"can:virtual:replay-{os.getpid()}")
    try:
        span_options = ["--start", "1.5", "--end", "3.6", "-q"]
        output = ["-o", str(folder / "from-tcp.mcap")]
        code, out, err = cli("replay", str(pcap), "--to", gimbal.to, *span_options, *output)
    finally:
        gimbal.close()
    assert code == 0, err
    span = read_span(pcap, 1.5, 3.6)
    commands = [f.data.hex(" ").upper() for f in span.frames if f.is_command]
    received = [e for e in gimbal.received if e.topic == TOPIC_COMMAND]
    assert [e.fields["raw"] for e in received][-len(commands) - 2 : -2] == commands
    assert [e.fields["name"] for e in received[-2:]] == ["gimbal_control", "forward"]
    status = [f.can_id for f in span.frames if not f.is_command]
    assert status.count(GPS_ID) == 2 and status.count(ALTITUDE_ID) == 2
    got = [e.topic for e in gimbal.received if e.topic.startswith("/uav/")]
    assert got.count("/uav/gps") == 2 and got.count("/uav/altitude") == 2  # on their CAN IDs
    frames = len(span.frames)
    assert f"sent {frames} of {frames} frames ({len(commands)} commands, 4 UAV status)" in out


@pytest.mark.slow
def test_a_can_flight_replays_over_tcp_with_its_commands_and_timing(
    runs: dict[str, Replay],
) -> None:
    run = runs["healthy"].finish()
    assert run.code == 0, run.err
    # The gimbal got the flight's commands, in order, and nothing of its own feedback.
    assert run.commands()[-134:-2] == flight_commands()
    assert TOPIC_GIMBAL_ATTITUDE not in {e.topic for e in run.gimbal.received}
    # The recording names the flight and the span, and holds the commands as sent.
    meta = McapRecording(run.folder / "bench.mcap").metadata()["gimbal-analyzer"]
    assert (meta["command"], meta["flight"], meta["flight_span"]) == (
        "replay",
        FLIGHT,
        "0.000-12.000 s",
    )
    events = list(read(run.folder / "bench.mcap"))
    began = next(e.time for e in events if e.fields.get("state") == "replay")
    sent = [e.time - began for e in events if e.topic == TOPIC_COMMAND and e.time >= began]
    span = read_span(ROOT / FLIGHT, 0.0, 12.0)
    wanted = [f.time - span.start for f in span.frames if f.is_command]
    late = [t - w for t, w in zip(sent, wanted, strict=False)]
    assert len(sent) == len(wanted) + 2  # and the centring after them
    # To the millisecond (this machine may be shared: a few may come later).
    assert statistics.median(late) < 0.002 and min(late) > -0.001 and max(late) < 0.5


def masked(lines: list[str]) -> list[str]:
    """Lines with every number as 0: the bench's own figures (its feedback's phase, how
    late a frame went) change from run to run, the words and the verdicts do not."""
    return [re.sub(r"\d+(\.\d+)?", "0", line) for line in lines]


def shown_outputs() -> dict[str, list[str]]:
    """The how-to's blocks that begin with a replay or compare command: their output."""
    blocks = read_blocks(HOWTO.read_text(encoding="utf-8").splitlines(), "docs/howto/replay.md")
    out = {}
    for block in blocks:
        commands = block.commands()
        if commands and block.text[0].startswith("$ gimbal-analyzer"):
            out[commands[0][1]] = block.output()
    return out


@pytest.mark.slow
def test_compare_finds_the_flights_lag_and_the_howto_shows_a_real_run(
    runs: dict[str, Replay], folder: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    healthy, lag = runs["healthy"].finish(), runs["lag"].finish()
    assert lag.code == 0, lag.err
    monkeypatch.chdir(folder)
    code, against_healthy, _ = cli("compare", FLIGHT, "bench.mcap")
    assert code == 1  # the flight's gimbal was 0.3 s late, the bench's is not
    code, json_lines, _ = cli("compare", FLIGHT, "bench.mcap", "--json")
    pairs = [json.loads(line) for line in json_lines.splitlines()[:-1]]
    assert [p["kind"] for p in pairs if p["differs"]] == ["stick movement"] * 2
    for pair in pairs:
        if pair["differs"]:
            assert pair["lag_s_a"] == pytest.approx(0.3, abs=0.05) and pair["lag_s_b"] < 0.05
            assert pair["why"].startswith("lag 0.30 | 0.0")
    code, against_lag, _ = cli("compare", FLIGHT, "bench-lag.mcap")
    assert code == 0  # this one reproduces the flight
    shown = shown_outputs()
    replay_command = (
        f"gimbal-analyzer replay {FLIGHT} --to tcp:127.0.0.1:2000 --end 12 -o bench.mcap"
    )
    runs_shown = {
        replay_command: healthy.out,
        f"gimbal-analyzer compare {FLIGHT} bench.mcap": against_healthy,
        f"gimbal-analyzer replay {FLIGHT} --to tcp:127.0.0.1:2001 --end 12 -o bench-lag.mcap": (
            lag.out + against_lag
        ),
    }
    assert set(runs_shown) <= set(shown), sorted(shown)
    for command, output in runs_shown.items():
        differences = compare_shown("exact", masked(shown[command]), masked(output.splitlines()))
        assert not differences, f"{command}:\n" + "\n".join(differences)


@pytest.mark.slow
def test_the_html_draws_both_attitude_tracks_on_one_time_axis(
    runs: dict[str, Replay], folder: Path, tmp_path: Path
) -> None:
    from tests.test_report_command import canvases, load

    runs["healthy"].finish()
    page = tmp_path / "compare.html"
    code, _, err = cli(
        "compare", str(folder / FLIGHT), str(folder / "bench.mcap"), "--html", str(page)
    )
    assert code == 1, err
    text = page.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>") and "Chart.js v4" in text
    assert "lag 0.30 | 0.0" in text and "<h2>Gimbal attitude</h2>" in text
    dom, console = load(page, tmp_path)
    assert not [line for line in console if "Error" in line], console
    drawn = canvases(dom)
    for plot in ("plot-pitch", "plot-yaw"):
        painted, points = drawn[plot]
        assert painted > 100 and points > 2 * 24, (plot, drawn)  # A's samples and B's
