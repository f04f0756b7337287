"""`replay` and `compare` on a simulated gimbal in virtual time: the logic, without waiting.

A demo flight (a pilot's stick, a re-sent target, a tracker, the UAV's status) is
replayed by the same player `gimbal-analyzer replay` runs, to a simulated gimbal in
virtual time (``tests.replay_bench``), and each bench recording is compared with the
flight by `gimbal-analyzer compare` itself. ``test_replay_command`` runs the command
over TCP and a CAN bus in real time.
"""

from __future__ import annotations

import io
import json
import socket
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path
from typing import Any

import pytest

from analyzer.check.offline import SimulatedBench
from analyzer.check.steps import select
from analyzer.cli import main
from analyzer.mcapio.write.sink import McapSink, recording_metadata
from analyzer.protocol.codec import encode_command
from analyzer.protocol.ids import (
    ALTITUDE_ID,
    CONTROL_ID,
    FEEDBACK_ID,
    GPS_ID,
    TEXT_END_ID,
    TEXT_ID,
    UAV_ATTITUDE_ID,
)
from analyzer.replay.flight import Span
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.engine import SimConfig
from analyzer.sim.faults import FaultConfig
from tests.replay_bench import read_span, replay_offline, write_flight

TICK_S = 0.01  # the virtual clock's step: a frame goes at most this late


@pytest.fixture(scope="module")
def flight(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_flight(tmp_path_factory.mktemp("flight") / "flight.log")


@pytest.fixture(scope="module")
def span(flight: Path) -> Span:
    return read_span(flight)


def cli(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = main(list(argv))
    return code, out.getvalue(), err.getvalue()


def compared(a: Path, b: Path) -> tuple[int, list[dict[str, Any]], dict[str, Any]]:
    """``compare A B --json``: the exit code, the pairs and the summary."""
    code, out, err = cli("compare", str(a), str(b), "--json")
    assert code in (0, 1), err
    *pairs, last = [json.loads(line) for line in out.splitlines()]
    return code, pairs, last["summary"]


def sent_frames(
    bench: SimulatedBench, began: float, ended: float
) -> list[tuple[float, int, bytes]]:
    """What the ground station's side put on the bench's bus while the span was replayed."""
    return [
        (f.time, f.can_id, f.data)
        for f in bench.frames
        if began <= f.time < ended and f.can_id != FEEDBACK_ID
    ]


# -- what is sent, and when ----------------------------------------------------------------------


def test_the_flights_commands_and_uav_status_go_in_order_with_their_intervals(
    span: Span, tmp_path: Path
) -> None:
    assert span.commands == 290 and span.status > 500  # stick, target, tracker; GPS ...
    assert span.skipped_feedback > 60  # the flight's own feedback ...
    assert all(f.can_id != FEEDBACK_ID for f in span.frames)  # ... is never among the frames
    outcome, bench = replay_offline(span, tmp_path / "bench.mcap")
    assert outcome.stopped == "" and outcome.sent == len(span.frames)
    assert outcome.began is not None and outcome.ended is not None
    sent = sent_frames(bench, outcome.began, outcome.ended)
    assert [(i, d) for _, i, d in sent] == [(f.can_id, f.data) for f in span.frames]
    kinds = {GPS_ID, ALTITUDE_ID, UAV_ATTITUDE_ID, TEXT_ID, TEXT_END_ID, CONTROL_ID}
    assert kinds <= {i for _, i, _ in sent}  # the commands and every kind of UAV status
    for (t, _, _), frame in zip(sent, span.frames, strict=True):
        assert -1e-6 <= (t - outcome.began) - (frame.time - span.start) < TICK_S + 1e-6


def test_the_span_and_the_speed(flight: Path, tmp_path: Path) -> None:
    part = read_span(flight, 8.0, 12.0)
    assert part.start_s == 8.0 and part.end_s == 12.0
    assert all(part.start <= f.time <= part.end for f in part.frames)
    assert {f.what.split()[0] for f in part.frames if f.is_command} == {"gimbal_control"}
    outcome, bench = replay_offline(part, tmp_path / "fast.mcap", speed=2.0)
    assert outcome.began is not None and outcome.ended is not None
    sent = sent_frames(bench, outcome.began, outcome.ended)
    assert len(sent) == len(part.frames)
    for (t, _, _), frame in zip(sent, part.frames, strict=True):  # at twice the speed
        assert -1e-6 <= (t - outcome.began) - (frame.time - part.start) / 2 < TICK_S + 1e-6


def test_it_first_brings_the_gimbal_to_the_attitude_the_span_began_with(
    flight: Path, tmp_path: Path
) -> None:
    part = read_span(flight, 7.0, 12.0)  # after the first stick movement: pan turned
    assert part.attitude is not None and abs(part.attitude.motor_yaw) > 20
    left = SimConfig(attitude=(-45.0, 120.0))  # where the last person left the gimbal
    outcome, bench = replay_offline(part, tmp_path / "aligned.mcap", left)
    arrival = outcome.arrival
    assert arrival is not None and arrival.reached and len(arrival.sent) == 2
    at_start = [s for s in bench.observer.samples if s.time <= (outcome.began or 0)][-1]
    assert at_start.pitch == pytest.approx(part.attitude.pitch, abs=1.0)
    assert at_start.motor_yaw == pytest.approx(part.attitude.motor_yaw, abs=1.0)

    outcome, bench = replay_offline(part, tmp_path / "unaligned.mcap", left, align=False)
    assert outcome.arrival is None
    before = [f for f in bench.frames if f.can_id == CONTROL_ID and f.time < (outcome.began or 0)]
    assert before == []  # --no-align: nothing before the flight's first frame
    first = [s for s in bench.observer.samples if s.time <= (outcome.began or 0)][-1]
    assert (first.pitch, first.motor_yaw) == (-45.0, 120.0)


def test_a_gimbal_that_goes_silent_stops_the_replay(span: Span, tmp_path: Path) -> None:
    silent = SimConfig(faults=FaultConfig(stop_at=10.0, stop_for=30.0))
    outcome, _ = replay_offline(span, tmp_path / "silent.mcap", silent)
    assert outcome.stopped.startswith("the gimbal went silent: no feedback for 3.0 s")
    assert 0 < outcome.sent < len(span.frames)
    assert outcome.began is not None and outcome.ended is not None
    assert outcome.ended - outcome.began < 10.0 + 3.5  # stopped right away

    mute = SimConfig(faults=FaultConfig(stop_at=0.0, stop_for=100.0))
    outcome, _ = replay_offline(span, tmp_path / "mute.mcap", mute)
    assert outcome.stopped.startswith("no feedback from the gimbal in 2 s")
    assert "Nothing of the flight was sent" in outcome.stopped and outcome.sent == 0
    assert outcome.began is None


# -- safety and usage ----------------------------------------------------------------------------


def test_values_outside_the_documents_ranges_are_refused(tmp_path: Path) -> None:
    too_far = encode_command("specified_angle", pitch_deg=-120, check_range=False)
    lines = [
        f"(1715684400.000000) can0 {CONTROL_ID:08X}#{encode_command('forward').hex().upper()}",
        f"(1715684401.000000) can0 {CONTROL_ID:08X}#{too_far.hex().upper()}",
        f"(1715684402.000000) can0 {CONTROL_ID:08X}#0F77010000000000",  # not in the document
        f"(1715684403.000000) can0 {CONTROL_ID:08X}#{encode_command('look_down').hex().upper()}",
    ]
    log = tmp_path / "bad.log"
    log.write_text("\n".join(lines) + "\n", encoding="utf-8")
    part = read_span(log)
    assert [f.what.split()[0] for f in part.frames] == ["forward", "look_down"]
    assert [f.refused for f in part.refused] == [
        "pitch_deg: -120.0 out of range [-100.0, 60.0] deg",
        "not a command of the document (S_ID 0x0F, CMD 0x77)",
    ]
    code, out, _ = cli("replay", str(log), "--dry-run")
    assert code == 0
    assert "refused, not sent: 2 frame(s) the document does not allow:" in out
    assert "out of range [-100.0, 60.0] deg" in out and "0F08" not in out.split("dry run")[1]


def test_a_flight_without_commands_is_a_clear_error(flight: Path, tmp_path: Path) -> None:
    feedback_only = tmp_path / "feedback.log"
    feedback_only.write_text(
        "".join(
            line + "\n"
            for line in flight.read_text(encoding="utf-8").splitlines()
            if "030F0001#" in line
        ),
        encoding="utf-8",
    )
    code, _, err = cli("replay", str(feedback_only), "--dry-run")
    assert code == 2
    assert err.strip().splitlines() == [
        f"gimbal-analyzer replay: error: {feedback_only} holds no ground-station command "
        "(only 73 feedback messages): nothing to replay"
    ]
    code, _, err = cli("replay", str(flight), "--dry-run", "--start", "34.5", "--end", "35.5")
    assert code == 2 and "no ground-station command from 34.5 s to 35.5 s" in err
    assert "(its commands are from 2.0 s to 32.5 s)" in err
    code, _, err = cli("replay", str(flight), "--dry-run", "--start", "5", "--end", "5")
    assert code == 2 and "--end 5 must be after --start 5" in err


def test_without_a_link_nothing_is_sent(flight: Path, tmp_path: Path) -> None:
    code, out, err = cli("replay", str(flight), "-o", str(tmp_path / "x.mcap"))
    assert code == 2 and out == ""
    assert "give the gimbal's link with --to" in err and "--dry-run shows" in err
    assert not (tmp_path / "x.mcap").exists()


def test_dry_run_prints_every_frame_in_the_links_framing_and_sends_nothing(
    flight: Path, span: Span
) -> None:
    listening = socket.create_server(("127.0.0.1", 0))
    listening.settimeout(0.2)
    port = listening.getsockname()[1]
    try:
        code, out, _ = cli("replay", str(flight), "--dry-run", "--to", f"tcp:127.0.0.1:{port}")
        with pytest.raises(TimeoutError):
            listening.accept()  # nobody connected
    finally:
        listening.close()
    assert code == 0
    shown = [line for line in out.splitlines() if line.startswith("  +")]
    assert len(shown) == len(span.frames)
    assert all(" TCP EB 90 0" in line for line in shown)  # 0x0A commands, 0x0B status
    assert "+   2.050 s  gimbal_control" in out
    code, out, _ = cli(
        "replay", str(flight), "--dry-run", "--to", "can:virtual:dry", "--speed", "2"
    )
    assert "+   1.025 s  gimbal_control" in out and f"{CONTROL_ID:08X}#0F04" in out
    assert " TCP " not in out


# -- compare: a flight and its replays -----------------------------------------------------------


def test_a_healthy_gimbal_behaves_as_in_the_flight(
    flight: Path, span: Span, tmp_path: Path
) -> None:
    replay_offline(span, tmp_path / "healthy.mcap")
    code, pairs, summary = compared(flight, tmp_path / "healthy.mcap")
    assert code == 0 and summary["differs"] is False and summary["differ"] == 0
    kinds = [p["kind"] for p in pairs]
    assert kinds.count("stick movement") == 3 and kinds.count("stick stop") == 3
    assert kinds.count("re-sent target") == 1 and kinds.count("tracking session") == 2
    for pair in pairs:
        assert pair["verdict_a"] == pair["verdict_b"] == "obeyed"
        assert pair["at_a"] == pytest.approx(pair["at_b"], abs=TICK_S)
        assert pair["differs"] is False and pair["why"] == ""


def test_a_sluggish_gimbal_differs_in_the_stick_movements_with_half_the_ratios(
    flight: Path, span: Span, tmp_path: Path
) -> None:
    sluggish = SimConfig(behaviour=Behaviour(speed=0.5))
    replay_offline(span, tmp_path / "sluggish.mcap", sluggish)
    code, pairs, summary = compared(flight, tmp_path / "sluggish.mcap")
    assert code == 1 and summary["differ"] == 3
    for pair in pairs:
        if pair["kind"] != "stick movement":
            assert not pair["differs"], pair
            continue
        assert pair["differs"] and pair["verdict_b"] == "partial"
        for axis in ("pan", "tilt"):
            if pair.get(f"{axis}_ratio_a") is not None:
                ratio = pair[f"{axis}_ratio_b"] / pair[f"{axis}_ratio_a"]
                assert ratio == pytest.approx(0.5, abs=0.05)
                assert f"{axis} ratio" in pair["why"] and "outside 75-133 %" in pair["why"]


def test_a_gimbal_ignoring_specified_angle_differs_in_those_pairs(
    flight: Path, span: Span, tmp_path: Path
) -> None:
    deaf = SimConfig(behaviour=Behaviour(ignore=frozenset({"specified_angle"})))
    replay_offline(span, tmp_path / "deaf.mcap", deaf)
    code, pairs, _ = compared(flight, tmp_path / "deaf.mcap")
    assert code == 1
    differing = [p for p in pairs if p["differs"]]
    assert [p["command"] for p in differing] == ["specified_angle"]
    assert differing[0]["verdict_b"] == "not_obeyed"
    assert differing[0]["why"].startswith("verdict obeyed | not_obeyed")


def test_the_json_names_every_figure_of_both_sides(
    flight: Path, span: Span, tmp_path: Path
) -> None:
    replay_offline(span, tmp_path / "keys.mcap")
    _, pairs, summary = compared(flight, tmp_path / "keys.mcap")
    for pair in pairs:
        assert {"command", "time_a", "time_b", "verdict_a", "verdict_b", "differs", "why"} <= set(
            pair
        )
    stick = next(p for p in pairs if p["kind"] == "stick movement")
    assert {"pan_ratio_a", "pan_ratio_b", "lag_s_a", "lag_s_b"} <= set(stick)
    target = next(p for p in pairs if p["kind"] == "re-sent target")
    assert {"response_s_a", "settle_s_b", "overshoot_deg_a", "error_deg_b"} <= set(target)
    assert set(summary) == {"a", "b", "pairs", "same", "differ", "only_a", "only_b", "differs"}


def test_the_table_shows_both_sides_and_why(flight: Path, span: Span, tmp_path: Path) -> None:
    replay_offline(span, tmp_path / "slow.mcap", SimConfig(behaviour=Behaviour(speed=0.5)))
    code, out, _ = cli("compare", str(flight), str(tmp_path / "slow.mcap"))
    assert code == 1
    lines = out.splitlines()
    assert lines[0] == f"A  {flight} (candump): 0.0 s to 36.0 s of it, the span the other replayed"
    assert lines[1].startswith(f"B  {tmp_path / 'slow.mcap'} (mcap of replay): its replay of")
    at = lines.index(next(line for line in lines if line.startswith("stick movement")))
    words = " ".join(lines[at].split())
    assert words == "stick movement gimbal_control 2.05 2.05 obeyed partial DIFFERS"
    assert lines[at + 1].strip() == "pan ratio 1.00 | 0.50, lag 0.00 | 0.00 s"
    assert lines[at + 2].strip() == "why: verdict obeyed | partial"
    assert lines[-1].startswith("9 pairs, 3 differ: the gimbal behaved differently")


# -- compare: two check recordings ---------------------------------------------------------------


def check_recording(path: Path, config: SimConfig) -> Path:
    bench = SimulatedBench(config)
    sink = McapSink(path, metadata=recording_metadata("check: sim", command="check"))
    bench.pipeline.sinks.append(sink)
    bench.check(select("pitch_angle,pan_speed,tracking"))
    bench.finish()
    return path


def test_two_check_recordings_are_compared_step_by_step(tmp_path: Path) -> None:
    one = check_recording(tmp_path / "fw1.mcap", SimConfig())
    two = check_recording(tmp_path / "fw2.mcap", SimConfig())
    slow = check_recording(tmp_path / "slow.mcap", SimConfig(behaviour=Behaviour(speed=0.4)))
    code, pairs, _ = compared(one, two)
    assert code == 0
    assert [(p["kind"], p["command"]) for p in pairs] == [
        ("check step", "pitch_angle"),
        ("check step", "pan_speed"),
        ("check step", "tracking"),
    ]
    code, pairs, _ = compared(one, slow)
    assert code == 1
    by_step = {p["command"]: p for p in pairs}
    assert by_step["pitch_angle"]["verdict_b"] == "fail"
    assert "slew 60.0 | 24.0 deg/s: B is 40 % of A" in by_step["pitch_angle"]["why"]
    assert "rate 20.0 | 8.0 deg/s: B is 40 % of A, outside 75-125 %" in by_step["pan_speed"]["why"]
    assert not by_step["tracking"]["differs"]


def test_unreadable_inputs_and_a_refused_output_are_usage_errors(
    flight: Path, tmp_path: Path
) -> None:
    code, _, err = cli("compare", str(flight), str(tmp_path / "missing.mcap"))
    assert code == 2 and "error:" in err and "Traceback" not in err
    page = tmp_path / "page.html"
    page.write_text("keep me", encoding="utf-8")
    code, _, err = cli("compare", str(flight), str(flight), "--html", str(page))
    assert code == 2 and "exists" in err and page.read_text(encoding="utf-8") == "keep me"
