"""`gimbal-analyzer simulate` from the command line: what it prints, how it ends, its errors."""

from __future__ import annotations

import re

import pytest

from analyzer.cli import main
from analyzer.commands.simulate import _is_loopback


def test_simulate_prints_what_it_does_and_ends_after_its_duration(
    capsys: pytest.CaptureFixture[str],
) -> None:
    args = ["simulate", "--on", "tcp:0", "--duration", "0.6", "--ranging", "--drop", "5%"]
    assert main([*args, "--seed", "1", "--stop-feedback-at", "10"]) == 0
    out = capsys.readouterr().out
    first = out.splitlines()[0]
    assert first.startswith(
        "simulated gimbal, type 1 (35x zoom 2MP / 30x zoom 4K), on tcp:127.0.0.1:"
    )
    assert "as the IDU (TCP server)" in out
    assert "ranging feedback: every 2 s, in place of an attitude message" in out
    assert "faults: drop 5%, no feedback from 10 s for 3 s (seed 1)" in out
    assert "stops after 0.6 s" in out
    assert "done: 0 command(s) acted on" in out
    assert re.search(r"sent \d+ attitude, \d+ ranging", out)


def test_simulate_on_a_virtual_bus_says_it_is_in_process_only(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["simulate", "--duration", "0.1", "--quiet", "--uav"]) == 0
    out = capsys.readouterr().out
    assert "on can:virtual:gimbal-demo" in out
    assert "only reaches this process" in out
    assert "UAV: GPS 5 Hz" in out


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--on", "udp:1"], "expected can:INTERFACE:CHANNEL"),
        (["--gimbal-type", "6"], "--gimbal-type 6: valid: 1 (35x"),
    ],
)
def test_simulate_usage_errors(
    capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    assert main(["simulate", *args]) == 2
    assert message in capsys.readouterr().err


def test_bad_fault_rate_is_refused_by_the_parser(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["simulate", "--drop", "150%"])
    assert "a rate must be between 0 and 1" in capsys.readouterr().err


def test_loopback_detection() -> None:
    assert _is_loopback("127.0.0.1") and _is_loopback("::1") and _is_loopback("localhost")
    assert not _is_loopback("0.0.0.0") and not _is_loopback("192.168.42.200")


def test_heading_and_the_wrong_yaw_frame_from_the_command_line(
    capsys: pytest.CaptureFixture[str],
) -> None:
    args = ["simulate", "--duration", "0.1", "--heading", "390", "--geodetic-as-airframe"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "aircraft heading: 30 deg (psi = heading + yaw motor angle)" in out
    assert "behaviour: takes geodetic yaw targets from the airframe's nose" in out
    with pytest.raises(SystemExit):
        main(["simulate", "--heading", "north"])
    assert "'north' is not an angle in degrees" in capsys.readouterr().err
