"""Long file work shows how far it is and how fast it goes, on a terminal only.

Every command that reads a file through the pipeline (``decode``, ``analyze``,
``convert``, ``report``, ``table`` for a file it reads itself) draws the same line on stderr when it is a terminal, clears it
at the end, and stays quiet with -q or when stderr is a pipe or a file.
"""

from __future__ import annotations

import io
import os
import subprocess
import sys
from pathlib import Path

import pytest

from analyzer.inputs import open_input
from analyzer.mcapio.read.video import read_thumbnails, thumbnail_times
from analyzer.mcapio.write.sink import McapSink
from analyzer.mcapio.write.video import write_frames
from analyzer.pipeline import Pipeline, run_items
from analyzer.progress import Progress, further_pass
from analyzer.video.rtsp_stream import VideoFrame
from tests.platforms import pseudo_terminals

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "samples" / "flight-candump.log"


def run_on_a_terminal(*args: str, cwd: Path) -> tuple[int, str]:
    """Run the command with stderr on a pseudo-terminal (stdout a pipe); what it drew."""
    main, child = os.openpty()
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen(
        [sys.executable, "-m", "analyzer", *args],
        stdout=subprocess.DEVNULL,
        stderr=child,
        stdin=subprocess.DEVNULL,
        cwd=cwd,
        env=env,
    )
    os.close(child)
    drawn = b""
    while True:
        try:
            chunk = os.read(main, 4096)
        except OSError:  # the child closed the terminal
            break
        if not chunk:
            break
        drawn += chunk
    os.close(main)
    return proc.wait(timeout=60), drawn.decode(errors="replace")


COMMANDS = {
    "decode": ("decode", str(SAMPLE), "--summary"),
    "analyze": ("analyze", str(SAMPLE)),
    "convert": ("convert", str(SAMPLE), "-o", "out.mcap"),
    "report": ("report", str(SAMPLE), "-o", "out.html"),
    "table": ("table", str(SAMPLE), "-o", "fleet"),
}


@pytest.mark.parametrize("name", sorted(COMMANDS))
@pseudo_terminals
def test_every_command_draws_the_same_progress_line(name: str, tmp_path: Path) -> None:
    code, drawn = run_on_a_terminal(*COMMANDS[name], cwd=tmp_path)
    assert code == 0, drawn
    assert "flight-candump.log [##############################] 100.0%" in drawn
    assert "MB/s" in drawn and "frames/s" in drawn
    assert "\r\033[K" in drawn  # cleared before the command's own last words


@pytest.mark.parametrize("name", ["analyze", "convert", "report", "table"])
@pseudo_terminals
def test_quiet_draws_nothing(name: str, tmp_path: Path) -> None:
    code, drawn = run_on_a_terminal(*COMMANDS[name], "-q", cwd=tmp_path)
    assert code == 0 and "%" not in drawn and "MB/s" not in drawn


class Reader:
    source = "big.log"
    size_bytes = 1000
    position_bytes = 250


class Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_only_on_a_terminal_that_output_does_not_use() -> None:
    assert Progress.maybe(Reader(), io.StringIO()) is None  # stderr a pipe
    assert Progress.maybe(Reader(), Tty(), quiet=True) is None
    assert Progress.maybe(Reader(), Tty(), Tty(), quiet_output=False) is None  # lines show it
    sized = Reader()
    sized.size_bytes = None  # type: ignore[assignment]
    assert Progress.maybe(sized, Tty()) is None  # standard input: no size
    err = Tty()
    progress = Progress.maybe(Reader(), err, label="reading ")
    assert progress is not None
    progress.update(500)
    progress.clear()
    text = err.getvalue()
    assert text.startswith("\rreading big.log [#######.......") and " 25.0%" in text
    assert "frames/s" in text and text.endswith("\r\033[K")


def _positions(path: Path) -> tuple[list[int], int]:
    reader = open_input(str(path), None, 2000)
    seen = []
    for _ in reader:
        seen.append(reader.position_bytes)
    return seen, path.stat().st_size


@pytest.mark.parametrize("finished", [True, False])
def test_a_recording_read_again_says_how_far_the_read_has_got(
    finished: bool, tmp_path: Path
) -> None:
    """The bar of analyze, report, convert or table of a recording moves with the chunks
    read, for a finished file (read through its index) and a recovered one (read in order)."""
    path = tmp_path / "flight.mcap"
    sink = McapSink(path, metadata={"source": "test"}, flush_interval=None, chunk_size=2048)
    run_items(open_input(str(SAMPLE), None, 2000), Pipeline(sinks=[sink]))
    if not finished:
        data = path.read_bytes()
        path.write_bytes(data[: len(data) * 3 // 4])  # cut off by a power loss
    seen, size = _positions(path)
    assert seen == sorted(seen)  # never back
    middle = seen[len(seen) // 2]
    assert 0 < middle < size * 0.9  # moving during the read, not only at the end
    assert seen[-1] <= size and len(set(seen)) > 10


def test_a_further_pass_over_a_file_draws_its_own_line(tmp_path: Path) -> None:
    path = tmp_path / "flight.mcap"
    path.write_bytes(bytes(1000))
    err = Tty()
    with further_pass(str(path), err, label="pictures ") as read:
        assert read is not None
        read(500)
    text = err.getvalue()
    assert text.startswith("\rpictures ") and " 50.0%" in text and text.endswith("\r\033[K")
    with further_pass(str(path), Tty(), quiet=True) as read:
        assert read is None
    with further_pass(str(path), io.StringIO()) as read:
        assert read is None  # not a terminal


def test_the_camera_passes_of_a_report_say_how_far_they_have_got(tmp_path: Path) -> None:
    """``report`` of a recording reads the camera thumbnails twice more (their times, then
    the pictures): each pass tells its line how far through the file it is."""
    path = tmp_path / "camera.mcap"
    sink = McapSink(path, metadata={"source": "test"}, flush_interval=None, chunk_size=4096)
    frames = [
        VideoFrame("main", 1_700_000_000 + n / 2, os.urandom(3000), n % 4 == 0, "h264", 64, 36)
        for n in range(200)
    ]
    for frame in frames[::4]:
        frame.thumbnail = os.urandom(500)
    sink.write_with(lambda channels: write_frames(channels, frames))
    sink.close()
    size = path.stat().st_size
    told: list[int] = []
    assert len(thumbnail_times(path, told.append)) == 50
    assert len(told) == 50 and told == sorted(told) and 0 < told[25] < size
    told.clear()
    assert len(list(read_thumbnails(path, told.append))) == 50
    assert len(told) == 50 and told[-1] <= size
