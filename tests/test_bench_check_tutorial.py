"""docs/tutorials/bench-check.md shows real runs: here they run again and are compared.

Each ``real`` block of the page that runs ``check`` is run as the page runs it: its
simulator (the ``simulate`` command before it on the page) and the check, each a process
of its own, on a free loopback port instead of the page's, in a folder of its own, all
at once to keep the wall time short. What they print is compared with what the page
shows, line for line, with the figures that vary from run to run masked (``VARIES``):
the port, the recording's date, and what the bench's clock and the feedback's phase
decide (times, measured rates, slews). The verdicts, the steps, what was asked and the
limits are compared as shown. A ``real`` block that runs ``simulate`` shows that
simulator's terminal during the check.
"""

from __future__ import annotations

import re
import shlex
import subprocess
import threading
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

import pytest

from tests.readme_blocks import Block, read_blocks
from tests.readme_examples import compare
from tests.tool_runs import ToolRun, tool_process

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs/tutorials/bench-check.md"
LOOPBACK = re.compile(r"tcp:127\.0\.0\.1:(\d+)")

# The figures that vary from run to run, each masked where its group is: everything else
# (verdicts, step names, targets, the speeds asked, limits, counts of steps, messages lost
# and CRC errors, an overshoot of 0.0) must be as shown.
VARIES = tuple(
    re.compile(pattern)
    for pattern in (
        r"127\.0\.0\.1:(\d+)",  # a free port, not the page's
        r"check-(\d{8}-\d{6})\.mcap",  # the recording's local date and time
        r"^(\[\s*\d+\.\d+\])",  # the simulator's clock
        # The feedback's phase and how late each message is read on a busy computer:
        r"period (\d+\.\d+) s, messages (\d+)",
        r"(\d+) messages every (\d+\.\d+) s over (\d+\.\d+) s",
        r"slew (\d+\.\d+) deg/s",
        r"latency (\d+\.\d+) s",
        r"settle (\d+\.\d+) s",
        r"reached -?\d+\.\d+ in (\d+\.\d+) s",
        r"after (\d+\.\d+) s",
        r"still for (\d+\.\d+) s",
        r"rate (-?\d+\.\d+) deg/s",
        r"turned (-?\d+\.\d+) deg for (-?\d+\.\d+) commanded \((\d+) % by the fit over (\d+)",
        r"turned at (-?\d+\.\d+) deg/s for \d+ asked \((\d+) %",
        r"at (-?\d+\.\d+), (\d+\.\d+) deg from the target",
        r"moved at (\d+\.\d+) deg/s",
        # Short of the target: the last sample caught the gimbal on its way (0.00 at it).
        r"error (-?(?:0\.0*[1-9]\d*|[1-9]\d*\.\d+)) deg",
    )
)


def masked(lines: list[str]) -> list[str]:
    """Lines with each figure that varies as ``#``."""
    out = []
    for line in lines:
        for pattern in VARIES:
            line = pattern.sub(_hide, line)
        out.append(line)
    return out


def _hide(found: re.Match[str]) -> str:
    text, at = found.group(0), found.start()
    for group in range(len(found.groups()), 0, -1):
        if found.group(group) is not None:
            start, end = found.span(group)
            text = text[: start - at] + "#" + text[end - at :]
    return text


@dataclass
class Shown:
    """A ``real`` block: its command (as on the page) and its output, and the
    simulator the check ran against (the ``simulate`` command before it)."""

    block: Block
    command: str
    simulator: str

    @property
    def output(self) -> list[str]:
        return self.block.output()


def shown_runs() -> list[Shown]:
    """The page's ``real`` blocks, in order, each with the simulator it ran against."""
    blocks = read_blocks(PAGE.read_text(encoding="utf-8").splitlines(), "bench-check.md")
    simulator = ""
    out = []
    for block in blocks:
        for _, command in block.commands():
            if command.startswith("gimbal-analyzer simulate"):
                simulator = command
        if block.mode == "real":
            ((_, command),) = block.commands()
            out.append(Shown(block, command, simulator))
    return out


def argv(command: str, port: int) -> list[str]:
    """The arguments of a command line of the page, on ``port`` instead."""
    words = shlex.split(LOOPBACK.sub(f"tcp:127.0.0.1:{port}", command))
    assert words[0] == "gimbal-analyzer"
    return words[1:]


@dataclass
class Simulator:
    """``simulate`` as its own process on a free port; its terminal read as it prints."""

    command: str
    process: subprocess.Popen[str]
    lines: list[str] = field(default_factory=list)
    port: int = 0
    reader: threading.Thread | None = None

    @classmethod
    def start(cls, command: str) -> Simulator:
        process = tool_process(argv(command, 0), stderr=subprocess.STDOUT, PYTHONUNBUFFERED="1")
        simulator = cls(command, process)
        assert process.stdout is not None
        first = process.stdout.readline()
        simulator.lines.append(first.rstrip("\n"))
        found = LOOPBACK.search(first)
        assert found, f"{command}: {first!r}"
        simulator.port = int(found.group(1))
        simulator.reader = threading.Thread(target=simulator._read, daemon=True)
        simulator.reader.start()
        return simulator

    def _read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.append(line.rstrip("\n"))

    def stop(self) -> list[str]:
        """Stopped (it runs until then): every line it printed."""
        if self.process.poll() is None:
            self.process.terminate()
        self.process.wait(30)
        if self.reader is not None:
            self.reader.join(30)  # the lines still in the pipe
        return self.lines


@dataclass
class Run(ToolRun):
    """A check of the page against its simulator, in ``folder``."""

    shown: Shown = field(kw_only=True)
    simulator: Simulator = field(kw_only=True)
    folder: Path = field(kw_only=True)
    timeout_s: ClassVar[float] = 240.0

    def stop_gimbal(self) -> None:
        self.simulator.stop()


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Iterator[list[Run]]:
    started: list[Run] = []
    try:
        checks = [s for s in shown_runs() if s.command.startswith("gimbal-analyzer check")]
        for number, shown in enumerate(checks):
            folder = tmp_path_factory.mktemp(f"bench-check-{number}")
            simulator = Simulator.start(shown.simulator)
            process = tool_process(argv(shown.command, simulator.port), folder)
            started.append(Run(process, shown=shown, simulator=simulator, folder=folder))
        yield started
    finally:
        for run in started:
            run.abandon()


@pytest.mark.slow
def test_every_check_the_tutorial_shows_prints_that_now(runs: list[Run]) -> None:
    # The healthy gimbal, the sluggish one and the one left looking down and right.
    assert [run.shown.simulator.split("--on ")[1] for run in runs] == [
        "tcp:127.0.0.1:2000",
        "tcp:127.0.0.1:2001 --sluggish 0.4",
        "tcp:127.0.0.1:2002 --start-pitch -45 --start-yaw 120",
    ]
    stale = []
    for run in runs:
        printed = run.finish().out.splitlines()
        differences = compare("exact", masked(run.shown.output), masked(printed))
        if differences:
            stale.append(f"{run.shown.command}:\n" + "\n".join(differences))
        failed = re.search(r"^\d+ passed, (\d+) failed", run.out, re.MULTILINE)
        assert failed, run.out
        assert run.code == (1 if int(failed.group(1)) else 0), run.err  # 1: a step failed
        recorded = next(line for line in printed if line.startswith("recorded to "))
        assert (run.folder / recorded.removeprefix("recorded to ")).is_file()
    assert not stale, "\n\n".join(stale)
    healthy, sluggish, _ = runs
    assert (healthy.folder / "bench.html").read_text(encoding="utf-8").startswith("<!DOCTYPE")
    # Without -o: check-YYYYMMDD-HHMMSS.mcap in the folder the check ran in, and nothing else.
    (recording,) = sluggish.folder.iterdir()
    assert re.fullmatch(r"check-\d{8}-\d{6}\.mcap", recording.name)
    assert f"recorded to {recording.name}" in sluggish.out


@pytest.mark.slow
def test_the_simulators_terminal_shows_the_steps_start_before_its_move(
    runs: list[Run],
) -> None:
    terminals = [s for s in shown_runs() if s.command.startswith("gimbal-analyzer simulate")]
    assert terminals, "the page shows no simulator's terminal"
    for terminal in terminals:
        (run,) = [r for r in runs if r.shown.simulator == terminal.command]
        printed = run.finish().simulator.stop()
        differences = compare("exact", masked(terminal.output), masked(printed))
        assert not differences, f"{terminal.command}:\n" + "\n".join(differences)


def test_every_real_run_the_page_shows_is_one_these_tests_run() -> None:
    """A check, or the terminal of a simulator a check ran against."""
    shown = shown_runs()
    checked = {s.simulator for s in shown if s.command.startswith("gimbal-analyzer check")}
    for run in shown:
        assert run.command.startswith("gimbal-analyzer check") or run.command in checked, run


def test_only_the_figures_that_vary_are_masked() -> None:
    line = (
        "pitch_angle   fail     slew 24.0 deg/s, latency 0.00 s, settle 5.49 s, "
        "overshoot 0.0 deg, error -3.19 deg"
    )
    assert masked([line]) == [
        "pitch_angle   fail     slew # deg/s, latency # s, settle # s, overshoot 0.0 deg, error # deg"
    ]
    kept = (
        "pitch_angle   pass     slew 60.0 deg/s, latency 0.00 s, overshoot 0.0 deg, error 0.00 deg"
    )
    assert masked([kept])[0].endswith("overshoot 0.0 deg, error 0.00 deg")
    asked = "pan_speed     fail     rate 8.0 deg/s, asked 20.0 deg/s"
    assert masked([asked]) == ["pan_speed     fail     rate # deg/s, asked 20.0 deg/s"]
    why = (
        "pitch -90.0 not reached within 5 s: still on its way, at -74.8, 15.2 deg from the "
        "target; moved at 24.0 deg/s, slower than the minimum 30 deg/s"
    )
    assert masked([why]) == [
        "pitch -90.0 not reached within 5 s: still on its way, at #, # deg from the target; "
        "moved at # deg/s, slower than the minimum 30 deg/s"
    ]
    assert masked(["[   2.55] rx forward", "recording check-20261128-234413.mcap"]) == [
        "# rx forward",
        "recording check-#.mcap",
    ]
