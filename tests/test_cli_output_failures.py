"""Standard output that cannot be written (/dev/full) or whose reader leaves (| head)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from analyzer.errors import EXIT_FAILED, EXIT_OK
from analyzer.mcapio.read.reader import McapRecording

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "samples" / "flight-candump.log"
ENV = {**os.environ, "PYTHONPATH": str(ROOT), "NO_COLOR": "1"}

needs_dev_full = pytest.mark.skipif(not os.path.exists("/dev/full"), reason="no /dev/full")


def run_to_dev_full(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    with open("/dev/full", "w", encoding="utf-8") as full:
        return subprocess.run(
            [sys.executable, "-m", "analyzer", *args],
            stdout=full,
            stderr=subprocess.PIPE,
            text=True,
            cwd=cwd,
            env=ENV,
            timeout=60,
            encoding="utf-8",
        )


def one_line_error(proc: subprocess.CompletedProcess[str], command: str) -> None:
    assert proc.returncode == EXIT_FAILED, proc.stderr
    assert "Traceback" not in proc.stderr
    assert "Exception ignored" not in proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith(f"gimbal-analyzer {command}: error: cannot write to standard output")
    assert "No space left on device" in lines[0]


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("rec") / "flight.mcap"
    subprocess.run(
        [sys.executable, "-m", "analyzer", "convert", str(SAMPLE), "-o", str(path), "-q"],
        check=True,
        env=ENV,
        timeout=60,
    )
    return path


@pytest.mark.slow
@needs_dev_full
@pytest.mark.parametrize(
    "args",
    [
        ("decode", str(SAMPLE)),
        ("decode", str(SAMPLE), "--summary"),
        ("decode", str(SAMPLE), "--json"),
        ("commands",),
        ("commands", "--markdown"),
        ("send", "--list"),
        ("send", "look_down"),
        ("interfaces",),
        ("interfaces", "--json"),
    ],
)
def test_full_standard_output_is_one_line_and_exit_1(args: tuple[str, ...], tmp_path: Path) -> None:
    one_line_error(run_to_dev_full(*args, cwd=tmp_path), args[0])


@needs_dev_full
@pytest.mark.parametrize("json", [False, True])
def test_info_to_a_full_standard_output(recording: Path, tmp_path: Path, json: bool) -> None:
    args = ["info", str(recording)] + (["--json"] if json else [])
    one_line_error(run_to_dev_full(*args, cwd=tmp_path), "info")


@needs_dev_full
def test_help_to_a_full_standard_output(tmp_path: Path) -> None:
    proc = run_to_dev_full("--help", cwd=tmp_path)
    assert proc.returncode == EXIT_FAILED
    assert "Traceback" not in proc.stderr and "Exception ignored" not in proc.stderr


@pytest.mark.slow
@needs_dev_full
def test_demo_to_a_full_standard_output_finishes_its_recording(tmp_path: Path) -> None:
    proc = run_to_dev_full("demo", "--no-tui", "--duration", "0.5", "-o", "d.mcap", cwd=tmp_path)
    assert proc.returncode == EXIT_FAILED
    assert "Traceback" not in proc.stderr
    assert "cannot write to standard output: No space left on device" in proc.stderr
    assert not McapRecording(tmp_path / "d.mcap").recovered  # footer and summary written


def _read_one_line_then_close(args: list[str], cwd: Path) -> subprocess.Popen[bytes]:
    proc = subprocess.Popen(
        [sys.executable, "-m", "analyzer", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        cwd=cwd,
        env=ENV,
    )
    assert proc.stdout is not None and proc.stderr is not None
    assert proc.stdout.readline()
    proc.stdout.close()  # as `| head -1` does
    proc.wait(timeout=60)
    return proc


@pytest.mark.slow
def test_demo_piped_into_head_ends_quietly(tmp_path: Path) -> None:
    proc = _read_one_line_then_close(
        ["demo", "--no-tui", "--duration", "30", "-o", "d.mcap"], tmp_path
    )
    assert proc.stderr is not None
    err = proc.stderr.read().decode()
    assert proc.returncode == EXIT_OK, err
    assert "error" not in err.lower() and "Traceback" not in err
    assert not McapRecording(tmp_path / "d.mcap").recovered


def test_record_print_piped_into_head_ends_quietly(tmp_path: Path) -> None:
    args = ["record", "--source", f"file:{SAMPLE}", "--speed", "1", "-o", "r.mcap", "--print"]
    proc = _read_one_line_then_close(args, tmp_path)
    assert proc.stderr is not None
    err = proc.stderr.read().decode()
    assert proc.returncode == EXIT_OK, err
    assert "Traceback" not in err and "error" not in err.lower()
    assert "ended: output closed" in err
    assert not McapRecording(tmp_path / "r.mcap").recovered


def test_decode_piped_into_head_ends_quietly(tmp_path: Path) -> None:
    proc = _read_one_line_then_close(["decode", str(SAMPLE)], tmp_path)
    assert proc.stderr is not None
    err = proc.stderr.read().decode()
    assert proc.returncode == EXIT_OK and not err.strip()
