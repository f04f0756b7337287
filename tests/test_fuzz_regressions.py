"""Every input the fuzzers found a crash with is read again, by the target that found it.

``fuzz/regressions/TARGET/`` holds each input that once crashed, hung or blew up a
target (``python -m fuzz``): the target must now take it within the crash rules (only
ValueError / FileNotFoundError from the library, exit 0 or one ``error:`` line and exit
2 from the command line) and in less than the hang limit. Every target also takes its
own seeds, so that a target that stopped working is no silent loss of fuzzing.
"""

from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest

from fuzz.engine import REGRESSIONS
from fuzz.rules import HANG_S
from fuzz.targets import ALL, Target, targets

# Regression inputs run in under a second each; this much is a hang (a loaded machine
# and a first run that imports the readers stay well inside it).
LIMIT_S = 6 * HANG_S
REGRESSION_INPUTS = sorted(p for p in REGRESSIONS.glob("*/*") if p.is_file())


def run_bounded(target: Target, data: bytes) -> float:
    """``target.run(data)`` in a thread: its seconds; a failure when it raised or did not
    end within LIMIT_S (the thread is left behind, the test fails at once)."""
    raised: list[BaseException] = []

    def run() -> None:
        try:
            target.run(data)
        except BaseException as exc:
            raised.append(exc)

    start = time.monotonic()
    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(LIMIT_S)
    took = time.monotonic() - start
    if thread.is_alive():
        pytest.fail(f"{target.name}: still running after {LIMIT_S:.0f} s (a hang)")
    if raised:
        raise raised[0]
    return took


def test_the_regression_corpus_is_kept_by_target_name() -> None:
    names = {path.parent.name for path in REGRESSION_INPUTS}
    assert names and names <= set(targets()) - {ALL}, names
    assert all(path.stat().st_size <= 64 * 1024 for path in REGRESSION_INPUTS)


@pytest.mark.parametrize("path", REGRESSION_INPUTS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_a_crash_found_by_fuzzing_stays_fixed(path: Path) -> None:
    run_bounded(targets()[path.parent.name], path.read_bytes())


@pytest.mark.slow
@pytest.mark.parametrize("name", [name for name in targets() if name != ALL])
def test_every_target_takes_its_seeds(name: str) -> None:
    target = targets()[name]
    seeds = target.seeds()
    assert seeds, f"{name} has no seeds"
    for seed in seeds:
        run_bounded(target, seed)


def test_the_rules_take_documented_errors_and_one_error_line_only() -> None:
    from fuzz.rules import library, one_error_line

    def undocumented() -> None:
        raise KeyError("not a documented error")

    with pytest.raises(KeyError):
        library(undocumented)
    assert library(lambda: int("x")) is None  # ValueError: documented
    error = "gimbal-analyzer decode: error: cannot read x.blf as blf: ...\n"
    assert one_error_line("decode", 2, error)
    assert one_error_line("decode", 2, error + "  a detail it lists\n")
    assert one_error_line("decode", 0, "note: 3 lines were skipped\n")
    assert not one_error_line("decode", 1, error)  # exit 1 is no input error
    assert not one_error_line("decode", 2, error + "a second line\n")
    assert not one_error_line("decode", 2, "Traceback (most recent call last):\n")
    assert not one_error_line("decode", 0, "something on stderr\n")


def test_the_command_line_s_own_usage_errors_count_as_exit_codes() -> None:
    from fuzz.rules import run_cli

    code, _, err = run_cli(["decode", "x.log", "--format", "nonsense"])
    assert code == 2 and err.startswith("gimbal-analyzer decode: error: ")


def test_the_reliability_page_names_every_target() -> None:
    page = (REGRESSIONS.parent.parent / "docs" / "explanation" / "reliability.md").read_text(
        encoding="utf-8"
    )
    missing = [name for name in targets() if f"`{name}`" not in page]
    assert not missing, f"docs/explanation/reliability.md does not name {missing}"
