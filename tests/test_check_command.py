"""`gimbal-analyzer check` against the simulated gimbal, over the virtual CAN bus and over TCP.

A healthy gimbal passes every step (zoom is skipped: the feedback does not report it)
with its true slew rate (60 deg/s) and the speeds asked for; each fault of the
simulator fails the steps it should and no other. To keep the wall time short, every
TCP run is started at once (the check as its own process, the way a user runs it,
against a simulated gimbal in this process) while the CAN run goes on here.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import select
import signal
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import can
import jsonschema
import pytest
from mcap.reader import make_reader

from analyzer.cli import main
from analyzer.commands import simulate
from analyzer.protocol.check_fields import STEP_NAMES
from analyzer.protocol.schema import topic_schemas
from analyzer.protocol.types import Event
from analyzer.sim.engine import SimConfig, SimulatedGimbal
from analyzer.sim.runner import SimulatorRunner
from analyzer.sim.transports import SimulatedLink, TcpServerLink, open_gimbal_link, parse_link
from tests.platforms import posix_signals
from tests.test_report_command import load
from tests.tool_runs import ToolRun, tool_process

# Real checks over TCP in real time: each takes seconds.
pytestmark = pytest.mark.slow

# Short waits: the slowest healthy move (150 deg at 60 deg/s) takes 2.5 s.
FAST = ("--time-allowed", "4", "--listen", "2", "--speed-for", "1.5")
SLEW_DPS = 60.0


class Gimbal:
    """A simulated gimbal in a thread; with TCP it starts when the check connects, so
    the fault times (--stop-feedback-at) count from the check's start."""

    def __init__(self, on: str, *simulate_flags: str) -> None:
        parser = argparse.ArgumentParser()
        simulate.add_arguments(parser)  # the flags exactly as `simulate` takes them
        args = parser.parse_args(["--on", on, *simulate_flags])
        self.config = SimConfig(
            faults=simulate.fault_config(args),
            behaviour=simulate.behaviour(args),
            heading_deg=args.heading,
            attitude=(args.start_pitch, args.start_yaw),
        )
        self.duration: float | None = args.duration  # then it goes away, link and all
        self.link: SimulatedLink = open_gimbal_link(parse_link(on))
        self.to = on if on.startswith("can:") else self.link.name
        self.runner: SimulatorRunner | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        if isinstance(self.link, TcpServerLink):  # the gimbal starts when the check connects
            while not self.link.peers and not self._stop.is_set():
                self.link.receive(0.02)  # accepts the ground station
        runner = SimulatorRunner(
            SimulatedGimbal(time.monotonic(), self.config), self.link, status_every=None
        )
        runner.keep_received = True
        self.runner = runner
        if not self._stop.is_set():
            runner.run(self.duration)
        if self.duration is not None:
            self.link.close()

    @property
    def received(self) -> list[Event]:
        return self.runner.received if self.runner is not None else []

    def close(self) -> None:
        self._stop.set()
        if self.runner is not None:
            self.runner.stop()
        self._thread.join(5.0)
        with contextlib.suppress(OSError):
            self.link.close()


class SerialPair:
    """Two pseudo-terminals wired back to back: a serial cable between two devices."""

    def __init__(self) -> None:
        pairs = [os.openpty() for _ in range(2)]
        self.masters = [master for master, _ in pairs]
        self._slaves = [slave for _, slave in pairs]
        self.paths = [os.ttyname(slave) for slave in self._slaves]
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._relay, daemon=True)
        self._thread.start()

    def _relay(self) -> None:
        a, b = self.masters
        while not self._stop.is_set():
            ready, _, _ = select.select([a, b], [], [], 0.05)
            for fd in ready:
                with contextlib.suppress(OSError):
                    data = os.read(fd, 4096)
                    os.write(b if fd == a else a, data)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(2.0)
        for fd in self.masters + self._slaves:
            with contextlib.suppress(OSError):
                os.close(fd)


@dataclass
class Run(ToolRun):
    """A check run as a separate process (its steps: what it printed with --json)."""

    gimbal: Gimbal = field(kw_only=True)
    output: Path = field(kw_only=True)

    def stop_gimbal(self) -> None:
        self.gimbal.close()

    @property
    def steps(self) -> list[dict[str, Any]]:
        return [json.loads(line) for line in self.out.splitlines() if line.strip()]

    def by_name(self) -> dict[str, dict[str, Any]]:
        return {step["step"]: step for step in self.steps}


def start_check(gimbal: Gimbal, output: Path, *options: str) -> Run:
    args = ["check", "--to", gimbal.to, "--json", "-o", str(output), *FAST, *options]
    return Run(tool_process(args), gimbal=gimbal, output=output)


# name -> (simulate flags, check options): started together, judged by the tests below.
TCP_RUNS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "healthy": ((), ()),
    "sluggish": (("--sluggish", "0.4"), ("--steps", "pitch_angle,pan_speed")),
    "fall_short": (("--fall-short", "0.7"), ("--steps", "pitch_angle")),
    "ignore_tracking": (("--ignore", "tracking"), ()),
    "geodetic": (
        ("--geodetic-as-airframe", "--heading", "30"),
        ("--steps", "yaw_airframe,yaw_geodetic"),
    ),
    "drop": (("--drop", "0.3", "--seed", "1"), ("--steps", "feedback", "--listen", "6")),
    # Left looking down and to the right by the last person at the bench.
    "left_anywhere": (("--start-pitch", "-45", "--start-yaw", "120"), ("--steps", "pitch_angle")),
    # Silent from 2.5 s to 7.5 s after the check connected: the steps in it are run
    # again once the feedback is back.
    "link_lost": (("--duration", "5"), ("--steps", "pitch_angle,yaw_airframe,look_down")),
    "silence": (
        ("--stop-feedback-at", "2.5", "--stop-feedback-for", "5"),
        ("--steps", "pitch_angle,yaw_airframe,look_down"),
    ),
}


@pytest.fixture(scope="module")
def tcp_runs(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Run]]:
    folder = tmp_path_factory.mktemp("check-tcp")
    runs = {}
    try:
        for name, (flags, options) in TCP_RUNS.items():
            gimbal = Gimbal("tcp:127.0.0.1:0", *flags)
            runs[name] = start_check(gimbal, folder / f"{name}.mcap", *options)
        yield runs
    finally:
        for run in runs.values():
            run.abandon()


def check_in_process(gimbal: Gimbal, *options: str) -> tuple[int, list[dict[str, Any]], str]:
    out, err = io.StringIO(), io.StringIO()
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = main(["check", "--to", gimbal.to, "--json", *FAST, *options])
    finally:
        gimbal.close()
    steps = [json.loads(line) for line in out.getvalue().splitlines() if line.strip()]
    return code, steps, err.getvalue()


def messages(path: Path, topic: str) -> list[dict[str, Any]]:
    with path.open("rb") as f:
        return [json.loads(m.data) for _, _, m in make_reader(f).iter_messages(topics=[topic])]


def assert_healthy(steps: list[dict[str, Any]]) -> None:
    assert [s["step"] for s in steps] == list(STEP_NAMES)
    for step in steps:
        expected = "skipped" if step["step"] == "zoom" else "pass"
        assert step["verdict"] == expected, step
        assert set(step) >= {"step", "verdict", "detail"}
    by_name = {s["step"]: s for s in steps}
    for name in ("forward", "pitch_angle", "yaw_airframe", "yaw_geodetic", "look_down"):
        figures = by_name[name]
        assert figures["slew_dps"] == pytest.approx(SLEW_DPS, rel=0.15), name
        assert abs(figures["error_deg"]) <= 1.0 and figures["overshoot_deg"] <= 1.0, name
        assert 0.0 <= figures["latency_s"] < 0.6 and figures["settle_s"] > 0, name
    for name in ("pan_speed", "tilt_speed"):
        figures = by_name[name]
        assert figures["rate_dps"] == pytest.approx(figures["asked_dps"], rel=0.15), name
    feedback = by_name["feedback"]
    assert feedback["period_s"] == pytest.approx(0.5, rel=0.15)
    assert feedback["lost"] == 0 and feedback["crc_errors"] == 0
    assert "zoom" in by_name["zoom"]["detail"]


def centred_last(commands: list[dict[str, Any]]) -> None:
    """The last two commands: speeds 0, then forward."""
    *_, stop, centre = commands
    assert stop["name"] == "gimbal_control"
    assert stop["pan_speed_dps"] == 0 and stop["tilt_speed_dps"] == 0
    assert centre["name"] == "forward"


# -- safety and usage ----------------------------------------------------------------------


def test_without_a_link_it_refuses_and_sends_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["check"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--to" in err
    assert list(tmp_path.iterdir()) == []  # no recording either


def test_dry_run_prints_the_frames_and_sends_nothing(capsys: pytest.CaptureFixture[str]) -> None:
    listener = can.Bus(interface="virtual", channel="check-dry", receive_own_messages=False)
    try:
        assert main(["check", "--dry-run", "--to", "can:virtual:check-dry"]) == 0
        assert listener.recv(timeout=0.3) is None
    finally:
        listener.shutdown()
    out = capsys.readouterr().out
    assert "nothing is sent" in out
    for name in STEP_NAMES:
        assert name in out
    assert "00000F01#0F08027CFC000000" in out  # specified_angle pitch -90
    assert "x40 every 50 ms" in out  # gimbal_control repeated for 2 s
    last = out.strip().splitlines()[-2:]
    assert "(centre)" in last[0] and "gimbal_control" in last[0] and "forward" in last[1]


@pytest.mark.parametrize(
    ("options", "words"),
    [
        (["--steps", "pitch,zoom"], "unknown step pitch"),
        (["--to", "tcp:"], "tcp"),
        (["--to", "can:virtual:x", "--min-slew", "0"], "must be above 0"),
    ],
)
def test_usage_errors_are_one_line_and_exit_2(
    options: list[str], words: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with contextlib.suppress(SystemExit):
        assert main(["check", *options]) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err


def test_help_explains_steps_safety_and_exit_codes(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["check", "--help"])
    out = capsys.readouterr().out
    for name in STEP_NAMES:
        assert name in out
    assert "Safety" in out and "Exit codes" in out and "Ctrl-C" in out


def test_an_existing_recording_is_never_replaced(tmp_path: Path) -> None:
    taken = tmp_path / "taken.mcap"
    taken.write_bytes(b"keep me")
    assert main(["check", "--to", "can:virtual:check-taken", "-o", str(taken)]) == 2
    assert taken.read_bytes() == b"keep me"


# -- a healthy gimbal ------------------------------------------------------------------------


@pytest.mark.slow
def test_healthy_gimbal_on_the_virtual_can_bus_passes_every_step(
    tcp_runs: dict[str, Run], tmp_path: Path
) -> None:
    gimbal = Gimbal("can:virtual:check-healthy")
    output, page = tmp_path / "healthy.mcap", tmp_path / "healthy.html"
    code, steps, err = check_in_process(gimbal, "-o", str(output), "--report", str(page))
    assert code == 0, err
    assert_healthy(steps)
    assert "the gimbal is stopped and centred" in err
    # The recording: the traffic both ways, the findings and the steps with their schema.
    frames = messages(output, "/can/frames")
    assert {f["direction"] for f in frames} >= {"tx", "rx"}
    assert messages(output, "/analysis/response")
    recorded = messages(output, "/check/steps")
    validator = jsonschema.Draft202012Validator(topic_schemas()["/check/steps"])
    for message in recorded:
        validator.validate(message)
    assert [m["verdict"] for m in recorded] == [s["verdict"] for s in steps]
    centred_last(messages(output, "/gimbal/command"))
    # The report: the steps table on top, in a real browser.
    dom, console = load(page, tmp_path)
    assert console == []
    assert dom.index('id="check-steps"') < dom.index("<h2>Overview</h2>")
    assert dom.count('class="v st-pass"') == 9
    # `report` of the recording later shows the same steps on top.
    later = tmp_path / "later.html"
    assert main(["report", str(output), "-o", str(later)]) == 0
    text = later.read_text(encoding="utf-8")
    assert text.index('id="check-steps"') < text.index("<h2>Overview</h2>")
    assert text.count('class="v st-pass"') == 9


@pytest.mark.slow
def test_healthy_gimbal_over_tcp_passes_every_step(tcp_runs: dict[str, Run]) -> None:
    run = tcp_runs["healthy"].finish()
    assert run.code == 0, run.err
    assert_healthy(run.steps)
    # What the gimbal received: the steps' commands, ending with speeds 0 and forward.
    commands = [e.fields for e in run.gimbal.received if e.topic == "/gimbal/command"]
    centred_last(commands)
    controls = [c for c in commands if c["name"] == "gimbal_control" and c["pan_speed_dps"]]
    assert len(controls) == 30  # 1.5 s every 50 ms
    tcp = messages(run.output, "/stream/bytes")
    assert {m["direction"] for m in tcp} == {"gs_to_idu", "idu_to_gs"}


# -- faults ----------------------------------------------------------------------------------


def test_a_sluggish_gimbal_fails_the_moves_and_the_speeds(tcp_runs: dict[str, Run]) -> None:
    run = tcp_runs["sluggish"].finish()
    assert run.code == 1
    steps = run.by_name()
    assert steps["pitch_angle"]["verdict"] == "fail"
    assert steps["pitch_angle"]["slew_dps"] == pytest.approx(0.4 * SLEW_DPS, rel=0.15)
    assert "slower than the minimum 30 deg/s" in steps["pitch_angle"]["detail"]
    assert steps["pan_speed"]["verdict"] == "fail"
    speed = steps["pan_speed"]
    assert speed["rate_dps"] == pytest.approx(0.4 * speed["asked_dps"], rel=0.15)
    assert "sluggish" in speed["detail"]


def test_a_step_first_brings_the_gimbal_to_its_start_from_where_it_was_left(
    tcp_runs: dict[str, Run],
) -> None:
    run = tcp_runs["left_anywhere"].finish()
    (step,) = run.steps
    assert run.code == 0 and step["verdict"] == "pass", step
    assert step["slew_dps"] == pytest.approx(SLEW_DPS, rel=0.15)
    assert step["target_deg"] == -90
    angles = [
        (e.fields["name"], e.fields.get("pitch_deg"))
        for e in run.gimbal.received
        if e.topic == "/gimbal/command"
    ]
    # to its start (pitch 45) first, then the move it judges; at the end, centred
    assert angles[:2] == [("specified_angle", 45.0), ("specified_angle", -90.0)]


def test_a_gimbal_that_falls_short_fails_with_the_error(tcp_runs: dict[str, Run]) -> None:
    run = tcp_runs["fall_short"].finish()
    assert run.code == 1
    step = run.by_name()["pitch_angle"]
    assert step["verdict"] == "fail"
    # brought to its start (45, asked again as it stopped short), then 70 % of 45 -> -90
    assert step["error_deg"] == pytest.approx(-40.5, abs=1.5)
    assert f"stopped short at {-90 - step['error_deg']:.1f}" in step["detail"]


@pytest.mark.slow
def test_a_gimbal_ignoring_tracking_fails_only_tracking(tcp_runs: dict[str, Run]) -> None:
    run = tcp_runs["ignore_tracking"].finish()
    assert run.code == 1
    verdicts = {s["step"]: s["verdict"] for s in run.steps}
    assert verdicts.pop("tracking") == "fail"
    assert verdicts.pop("zoom") == "skipped"
    assert set(verdicts.values()) == {"pass"}, run.steps
    assert "tracking flag" in run.by_name()["tracking"]["detail"]  # the analysis says why


def test_geodetic_taken_as_airframe_fails_only_yaw_geodetic(tcp_runs: dict[str, Run]) -> None:
    run = tcp_runs["geodetic"].finish()
    steps = run.by_name()
    assert steps["yaw_airframe"]["verdict"] == "pass"
    geodetic = steps["yaw_geodetic"]
    assert geodetic["verdict"] == "fail" and "as if DATA4 were 1" in geodetic["detail"]
    assert abs(geodetic["error_deg"]) == pytest.approx(30.0, abs=1.0)  # the heading


def test_dropped_feedback_shows_in_the_feedback_step(tcp_runs: dict[str, Run]) -> None:
    run = tcp_runs["drop"].finish()
    step = run.by_name()["feedback"]
    assert step["verdict"] == "fail" and step["lost"] > 0
    assert "lost" in step["detail"]


def test_a_step_the_feedback_went_silent_in_is_run_again(tcp_runs: dict[str, Run]) -> None:
    """The 5 s silence leaves a step that cannot be judged: it is run again from its
    start once the feedback is back, and passes, saying why it ran again."""
    run = tcp_runs["silence"].finish()
    assert run.code == 0, run.steps
    again = [step for step in run.steps if step.get("tries", 1) > 1]
    assert again, run.steps
    for step in again:
        assert step["verdict"] == "pass"
        assert (
            f"on try {step['tries']} of 3: the feedback did not allow a judgement"
            in (step["detail"])
        )
        assert "no feedback" in step["detail"]


@posix_signals
def test_ctrl_c_stops_and_centres_the_gimbal(tmp_path: Path) -> None:
    gimbal = Gimbal("tcp:127.0.0.1:0")
    run = start_check(
        gimbal, tmp_path / "stopped.mcap", "--steps", "pan_speed", "--speed-for", "20"
    )
    turning = ended_first = False
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:  # wait until it is turning
            if any(e.fields.get("pan_speed_dps") for e in gimbal.received):
                turning = True
                break
            if run.process.poll() is not None:
                break
            time.sleep(0.1)
        ended_first = run.process.poll() is not None
        run.process.send_signal(signal.SIGINT)
        run.finish()
    finally:
        run.abandon()
    print(run.out, run.err, sep="\n")  # shown when it fails
    assert turning and not ended_first  # Ctrl-C came while it turned
    assert run.code == 130
    commands = [e.fields for e in gimbal.received if e.topic == "/gimbal/command"]
    centred_last(commands)
    centred_last(messages(run.output, "/gimbal/command"))  # and the recording is finished


@pytest.mark.slow
@pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs pseudo-terminals")
def test_a_gimbal_on_a_serial_line_is_checked_the_same_way(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)  # the recording gets its default, timestamped name here
    cable = SerialPair()
    try:
        gimbal = Gimbal(f"serial:{cable.paths[0]}@115200")
        to = f"serial:{cable.paths[1]}@115200"
        out = io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
            code = main(["check", "--to", to, "--json", *FAST, "--steps", "pitch_angle"])
        gimbal.close()
    finally:
        cable.close()
    (step,) = [json.loads(line) for line in out.getvalue().splitlines()]
    assert code == 0 and step["verdict"] == "pass", step
    assert step["slew_dps"] == pytest.approx(SLEW_DPS, rel=0.15)
    (recording,) = tmp_path.glob("check-*.mcap")
    assert [m["step"] for m in messages(recording, "/check/steps")] == ["pitch_angle"]


def test_a_link_lost_midway_ends_the_check_with_one_line(tcp_runs: dict[str, Run]) -> None:
    run = tcp_runs["link_lost"].finish()
    assert run.code == 1
    assert run.steps[0]["step"] == "pitch_angle" and run.steps[0]["verdict"] == "pass"
    (error,) = [line for line in run.err.splitlines() if "error:" in line]
    assert "closed the connection" in error and "keeps everything up to then" in error
    assert "Traceback" not in run.err
    # The recording is finished and readable, with what was sent up to then.
    assert messages(run.output, "/gimbal/command")
