"""`gimbal-analyzer analyze`: findings as text and JSON, on every sample, a recording, a session."""

from __future__ import annotations

import io
import json
import socket
from pathlib import Path

import dpkt
import jsonschema
import pytest

from analyzer.cli import main
from analyzer.mcapio.read.reader import read_events
from analyzer.protocol.types import TO_IDU, CanFrame, StreamChunk
from analyzer.samplegen import write_samples
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.engine import SimConfig
from analyzer.sim.ground import Step
from analyzer.sim.offline import run_offline, run_offline_stream

ROOT = Path(__file__).resolve().parent.parent
SCHEMA = json.loads(
    (ROOT / "schemas" / "analysis.response.schema.json").read_text(encoding="utf-8")
)
START = 1_700_000_000.0


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(["analyze", *args])
    out, err = capsys.readouterr()
    return code, out, err


def candump(path: Path, frames: list[CanFrame]) -> Path:
    lines = [f"({f.time:.6f}) can0 {f.can_id:08X}#{f.data.hex().upper()}" for f in frames]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


SCRIPT = (
    Step(1.0, "specified_angle", {"yaw_deg": 45}),
    Step(7.0, "gimbal_control", {"tilt_speed_dps": -10}, until=9.0),
    Step(13.0, "tracking", {"x": 4096, "y": 4096, "width": 320, "height": 240}),
    Step(19.0, "look_down"),
)


def session(path: Path, behaviour: Behaviour | None = None) -> Path:
    config = SimConfig(behaviour=behaviour or Behaviour())
    frames, _ = run_offline(SCRIPT, 26.0, config, start=START)
    return candump(path, frames)


def findings(out: str) -> list[dict[str, object]]:
    found = [json.loads(line) for line in out.splitlines()]
    for finding in found:
        jsonschema.validate(finding, SCHEMA)
    return found


def test_a_gimbal_that_obeys(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, str(session(tmp_path / "good.log")))
    assert code == 0, err
    assert "tolerance 1 deg, time allowed 5 s" in out
    assert "times are UTC, 2023-11-14" in out
    assert "NOT OBEYED" not in out and "PARTIAL" not in out
    assert "verdicts: 5 obeyed, 0 partial, 0 not obeyed, 0 unknown" in out
    assert "feedback: 1 of 1 minute healthy; no gap (no message lost)" in out
    assert "feedback         feedback     healthy     feedback healthy over" in out
    assert "22:13:21.000Z  specified_angle  target       obeyed      yaw reached 45.0" in out


def test_a_gimbal_that_does_not(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = Behaviour(speed=0.4, ignore=frozenset({"tracking"}), drift_s=1.5, reach=0.5)
    code, out, _ = run(capsys, str(session(tmp_path / "bad.log", bad)), "--json")
    assert code == 0
    verdicts = {(f["command"], f["check"]): f["verdict"] for f in findings(out)}
    assert verdicts[("specified_angle", "target")] == "partial"  # stopped half way
    assert verdicts[("gimbal_control", "rate")] == "partial"  # sluggish
    assert verdicts[("gimbal_control", "stop")] == "not_obeyed"  # drifted on
    assert verdicts[("tracking", "tracking")] == "not_obeyed"
    code, text, _ = run(capsys, str(tmp_path / "bad.log"), "--problems")
    assert "obeyed " not in text.replace("not obeyed", "") and "NOT OBEYED" in text


def test_tolerance_and_time_allowed(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = session(tmp_path / "slow.log", Behaviour(speed=0.1))
    _, out, _ = run(capsys, str(path), "--json")
    look = next(f for f in findings(out) if f["command"] == "look_down")
    assert look["verdict"] == "partial"
    _, out, _ = run(capsys, str(path), "--json", "--time-allowed", "6.5", "--tolerance", "50")
    look = next(f for f in findings(out) if f["command"] == "look_down")
    assert look["verdict"] == "obeyed"
    with pytest.raises(SystemExit) as stop:
        run(capsys, str(path), "--tolerance", "0")
    assert stop.value.code == 2 and "must be a number above 0" in capsys.readouterr().err


def test_help_shows_the_defaults(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["analyze", "--help"])
    out = capsys.readouterr().out
    assert "(default 1 deg)" in out and "(default 5 s)" in out and "50 ms" in out


@pytest.fixture(scope="module")
def samples(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    return {p.name: p for p in write_samples(tmp_path_factory.mktemp("samples"))}


def test_every_sample(samples: dict[str, Path], capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, str(samples["flight-candump.log"]))
    assert code == 0
    # The sample's gimbal moves on its own script: the pitch command is not followed.
    assert "specified_angle  target       NOT OBEYED  pitch -45.0 not reached" in out
    assert "2 damaged messages" in out
    code, out, _ = run(capsys, str(samples["idu-tcp.pcap"]), "--json")
    assert code == 0 and len(findings(out)) >= 8
    code, out, err = run(capsys, str(samples["uart-dump.bin"]))
    assert code == 0 and "carries no timestamps" in err


def test_a_recording_gives_the_findings_of_its_source(
    samples: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    source = samples["flight-candump.log"]
    recording = tmp_path / "flight.mcap"
    assert main(["convert", str(source), "-o", str(recording), "-q"]) == 0
    capsys.readouterr()
    _, direct, _ = run(capsys, str(source), "--json")
    code, recorded, _ = run(capsys, str(recording), "--json")
    assert code == 0 and findings(recorded) == findings(direct)
    # The recording holds the same findings on /analysis/response, valid to the schema.
    stored = [e.to_dict() for e in read_events(recording) if e.topic == "/analysis/response"]
    for finding in stored:
        jsonschema.validate(finding, SCHEMA)
    by_time = sorted(findings(direct), key=lambda f: (f["time"], f["check"]))
    assert sorted(stored, key=lambda f: (f["time"], f["check"])) == by_time


def test_unreadable_input_is_a_usage_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, _, err = run(capsys, str(tmp_path / "missing.log"))
    assert code == 2 and "error" in err


# -- a gimbal on an aircraft at heading 30, as captured on the IDU's TCP port and on the bus ----

GS, IDU = ("10.0.0.5", 50312), ("10.0.0.200", 2000)
YAW_SCRIPT = (
    Step(1.0, "specified_angle", {"yaw_deg": 45}),
    Step(8.0, "specified_angle", {"yaw_deg": 200}),
    Step(15.0, "specified_angle", {"yaw_deg": 350, "coordinate_system": "airframe"}),
)


def tcp_pcap(path: Path, chunks: list[StreamChunk]) -> Path:
    """The chunks as tcpdump on the ground station would save them (Ethernet, IPv4)."""
    seq = {True: 1000, False: 9000}
    with path.open("wb") as f:
        writer = dpkt.pcap.Writer(f, linktype=dpkt.pcap.DLT_EN10MB)
        for chunk in chunks:
            up = chunk.direction == TO_IDU
            (src, sport), (dst, dport) = (GS, IDU) if up else (IDU, GS)
            tcp = dpkt.tcp.TCP(
                sport=sport, dport=dport, seq=seq[up], ack=seq[not up], flags=0x18, data=chunk.data
            )
            seq[up] += len(chunk.data)
            ip = dpkt.ip.IP(src=socket.inet_aton(src), dst=socket.inet_aton(dst), p=6, data=tcp)
            frame = dpkt.ethernet.Ethernet(src=b"\x02" * 6, dst=b"\x04" * 6, data=ip)
            writer.writepkt(bytes(frame), ts=chunk.time)
    return path


@pytest.mark.parametrize("link", ["tcp", "can"])
def test_heading_30_without_ff13_gives_no_false_stopped_short(
    link: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config = SimConfig(heading_deg=30.0)
    if link == "tcp":
        chunks, _ = run_offline_stream(YAW_SCRIPT, 22.0, config, start=START)
        path = tcp_pcap(tmp_path / "idu.pcap", chunks)
    else:
        frames, _ = run_offline(YAW_SCRIPT, 22.0, config, start=START)
        path = candump(tmp_path / "bus.log", frames)
    code, out, _ = run(capsys, str(path))
    assert code == 0 and "stopped short" not in out and "other way" not in out
    assert (
        "yaw reached 45.0" in out
        and "yaw measured from north (psi offset from motor yaw: 30.0 deg)" in out
    )
    _, out, _ = run(capsys, str(path), "--json")
    targets = [f for f in findings(out) if f["check"] == "target"]
    assert [f["target_deg"] for f in targets] == [45, 200, 350]
    assert [f["verdict"] for f in targets] == ["obeyed"] * 3
    assert [f["yaw_reference"] for f in targets] == ["north", "north", "airframe"]
    assert targets[2]["reference_reason"] == "command DATA4 = 1"


def test_findings_already_in_the_input_are_not_written_again() -> None:
    from analyzer.analysis.response import ResponseAnalyzer
    from analyzer.commands.analyze_output import FindingsOutput
    from analyzer.pipeline import Pipeline, run_items
    from analyzer.protocol.types import TOPIC_ANALYSIS_RESPONSE, Event
    from tests.log_makers import flight_frames

    def written(extra: list[Event]) -> list[str]:
        out = io.StringIO()
        pipeline = Pipeline()
        output = FindingsOutput(ResponseAnalyzer(), pipeline.tally, json_lines=True, problems=False)
        pipeline.stages.append(output.stage)
        pipeline.sinks.append(output.to(out))
        run_items([*flight_frames(), *extra], pipeline)
        return out.getvalue().splitlines()

    old = {"command": "look_down", "check": "target", "verdict": "obeyed", "detail": "recorded"}
    recorded = Event(TOPIC_ANALYSIS_RESPONSE, 1_715_680_810.0, "analysis", old)
    lines = written([recorded])
    assert lines == written([]) and len(lines) > 5
    assert all("recorded" not in line for line in lines)
    times = [json.loads(line)["time"] for line in lines]
    assert times == sorted(times)  # in time order, as they were decided
