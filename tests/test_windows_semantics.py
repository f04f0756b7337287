"""What Windows does differently, simulated here: each behaviour the tool relies on.

A Windows C runtime that writes \\n as \\r\\n unless a file is opened O_BINARY, an ``os``
without ``fchmod``, a USB stick whose file system refuses hard links with EINVAL, a pipe
whose closed reader gives EINVAL, Ctrl-Break and the console's close button (SIGBREAK),
a console that shows ANSI colours only in virtual-terminal mode, a coarse ``time.time``.
"""

from __future__ import annotations

import ast
import errno
import io
import itertools
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from analyzer import portable, stdio
from analyzer.ansi import ENABLE_VIRTUAL_TERMINAL_PROCESSING, ansi_ok
from analyzer.cli import main
from analyzer.errors import OutputClosed
from analyzer.mcapio.read.reader import McapRecording
from analyzer.output_file import OutputFile, write_output
from analyzer.progress import Progress
from analyzer.stdio import GuardedStdout, utf8_when_redirected
from analyzer.wall_clock import WallClock

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "samples" / "flight-candump.log"
FAKE_O_BINARY = 0x40000000  # no flag of Linux's open(): stripped before the real call


@pytest.fixture
def windows_runtime(monkeypatch: pytest.MonkeyPatch) -> Iterator[list[int]]:
    """``os.open`` as Windows' C runtime does it: a descriptor opened without O_BINARY
    writes each \\n as \\r\\n. Yields the flags of every open."""
    real_open = os.open
    seen: list[int] = []
    threads: list[threading.Thread] = []

    def translating(target: int) -> int:
        read_end, write_end = os.pipe()

        def copy() -> None:
            with os.fdopen(read_end, "rb") as source, os.fdopen(target, "wb") as sink:
                while chunk := source.read(65536):
                    sink.write(chunk.replace(b"\n", b"\r\n"))

        threads.append(threading.Thread(target=copy, daemon=True))
        threads[-1].start()
        return write_end

    def windows_open(path: object, flags: int, mode: int = 0o777, **kw: object) -> int:
        seen.append(flags)
        fd = real_open(path, flags & ~FAKE_O_BINARY, mode, **kw)  # type: ignore[arg-type]
        if flags & FAKE_O_BINARY or flags & (os.O_WRONLY | os.O_RDWR) == 0:
            return fd
        return translating(fd)

    monkeypatch.setattr(portable, "OPEN_FLAGS", portable.OPEN_FLAGS | FAKE_O_BINARY)
    # tempfile adds O_BINARY on Windows itself (tempfile._bin_openflags)
    monkeypatch.setattr(tempfile, "_bin_openflags", tempfile._bin_openflags | FAKE_O_BINARY)
    monkeypatch.setattr(os, "open", windows_open)
    yield seen
    for thread in threads:
        thread.join(timeout=10)


def test_the_simulated_runtime_translates_without_o_binary(
    windows_runtime: list[int], tmp_path: Path
) -> None:
    fd = os.open(tmp_path / "text.bin", os.O_WRONLY | os.O_CREAT)
    os.write(fd, b"\x89MCAP0\r\n\n")
    os.close(fd)
    time.sleep(0.2)
    assert (tmp_path / "text.bin").read_bytes() == b"\x89MCAP0\r\r\n\r\n"


def test_a_live_recording_keeps_its_bytes_under_the_windows_runtime(
    windows_runtime: list[int], tmp_path: Path
) -> None:
    out = tmp_path / "flight.mcap"
    recording = OutputFile(out, atomic=False)  # how the MCAP sink of record / demo writes
    recording.file.write(b"\x89MCAP0\r\n" + bytes(range(256)) * 4)  # type: ignore[arg-type]
    recording.close_keep()
    assert all(flags & FAKE_O_BINARY for flags in windows_runtime)
    assert out.read_bytes() == b"\x89MCAP0\r\n" + bytes(range(256)) * 4


def test_convert_writes_a_readable_recording_under_the_windows_runtime(
    windows_runtime: list[int], tmp_path: Path
) -> None:
    out = tmp_path / "flight.mcap"
    assert main(["convert", str(SAMPLE), "-o", str(out), "-q"]) == 0
    writes = [flags for flags in windows_runtime if flags & (os.O_WRONLY | os.O_RDWR)]
    assert writes and all(flags & FAKE_O_BINARY for flags in writes)
    assert McapRecording(out).summary().statistics.message_count > 0


def test_every_os_open_of_the_analyzer_goes_through_portable_open_fd() -> None:
    direct = []
    for path in sorted((ROOT / "analyzer").rglob("*.py")):
        if path.name == "portable.py":
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Attribute)
                and node.func.attr == "open"
                and isinstance(node.func.value, ast.Name)
                and node.func.value.id == "os"
            ):
                direct.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert not direct, f"os.open without O_BINARY (use analyzer.portable.open_fd): {direct}"


def test_outputs_are_written_where_os_has_no_fchmod(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.delattr(os, "fchmod", raising=False)  # Windows before 3.13
    old = os.umask(0o022)
    try:
        write_output(tmp_path / "gimbal.dbc", 'VERSION ""\n')
        assert main(["export", "dbc", "-o", str(tmp_path / "export.dbc")]) == 0
    finally:
        os.umask(old)
    if sys.platform != "win32":  # POSIX permissions: set by the file's name instead
        assert (tmp_path / "gimbal.dbc").stat().st_mode & 0o777 == 0o644
    assert (tmp_path / "export.dbc").read_text(encoding="utf-8").startswith("VERSION")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["export.dbc", "gimbal.dbc"]


def test_a_file_system_that_refuses_hard_links_with_einval_gets_the_output(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    def no_links(source: object, target: object) -> None:
        raise OSError(errno.EINVAL, "Invalid argument")  # FAT / exFAT on Windows

    monkeypatch.setattr(os, "link", no_links)
    write_output(tmp_path / "report.html", "<html>")
    assert (tmp_path / "report.html").read_text(encoding="utf-8") == "<html>"
    assert [p.name for p in tmp_path.iterdir()] == ["report.html"]


class ClosedPipe(io.StringIO):
    """Standard output whose reader went away, as Windows reports it: EINVAL."""

    def write(self, text: str) -> int:
        raise OSError(errno.EINVAL, "Invalid argument")


def test_einval_from_a_closed_pipe_on_windows_is_a_quiet_end(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(sys, "platform", "win32")
    with pytest.raises(OutputClosed):
        GuardedStdout(ClosedPipe()).write("line\n")


def test_einval_elsewhere_is_an_error_still(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sys, "platform", "linux")
    with pytest.raises(Exception) as raised:
        GuardedStdout(ClosedPipe()).write("line\n")
    assert not isinstance(raised.value, OutputClosed)


def test_decode_into_a_closed_windows_pipe_exits_quietly(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(sys, "platform", "win32")
    monkeypatch.setattr(sys, "stdout", ClosedPipe())
    monkeypatch.setattr(stdio, "silence_stdout", lambda: None)
    assert main(["decode", str(SAMPLE)]) == 0
    assert capsys.readouterr().err == ""


# A subprocess in which SIGUSR1 plays Windows' SIGBREAK (Ctrl-Break, the console closed).
BREAK_CARRIER = """
import signal, sys
signal.SIGBREAK = signal.SIGUSR1
from analyzer.cli import main
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.skipif(not hasattr(signal, "SIGUSR1"), reason="needs SIGUSR1 to play SIGBREAK")
def test_ctrl_break_finishes_a_recording_as_ctrl_c_does(tmp_path: Path) -> None:
    out = tmp_path / "demo.mcap"
    proc = subprocess.Popen(
        [sys.executable, "-c", BREAK_CARRIER, "demo", "--no-tui", "--duration", "60",
         "-o", str(out)],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, encoding="utf-8",
    )  # fmt: skip
    assert proc.stdout is not None
    for _ in range(200):  # until the demo prints its first decoded line
        if proc.stdout.readline().strip():
            break
    time.sleep(1.0)
    proc.send_signal(signal.SIGUSR1)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    assert McapRecording(out).summary().statistics.message_count > 0  # finished: with its summary


class FakeConsole:
    """Windows' console: a mode, and whether SetConsoleMode takes virtual-terminal mode."""

    def __init__(self, mode: int | None, accepts: bool) -> None:
        self.mode_value, self.accepts = mode, accepts

    def mode(self, fd: int) -> int | None:
        return self.mode_value

    def set_mode(self, fd: int, mode: int) -> bool:
        if self.accepts:
            self.mode_value = mode
        return self.accepts


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True

    def fileno(self) -> int:
        return 1


def test_a_windows_console_gets_colours_once_its_vt_mode_is_on() -> None:
    console = FakeConsole(0x3, accepts=True)
    assert ansi_ok(Terminal(), platform="win32", console=console)
    assert console.mode_value == 0x3 | ENABLE_VIRTUAL_TERMINAL_PROCESSING


def test_an_old_windows_console_gets_no_escapes() -> None:
    assert not ansi_ok(Terminal(), platform="win32", console=FakeConsole(0x3, accepts=False))
    assert not ansi_ok(Terminal(), platform="win32", console=FakeConsole(None, accepts=True))
    assert not ansi_ok(io.StringIO(), platform="linux")  # not a terminal
    assert ansi_ok(Terminal(), platform="linux")


def test_the_progress_line_on_an_old_windows_console_is_plain_text(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr("analyzer.progress.ansi_ok", lambda stream: False)

    class Reader:
        source, size_bytes, position_bytes = "flight.log", 1000, 500

    line = Terminal()
    progress = Progress(Reader(), line)  # type: ignore[arg-type]
    progress.update(10)
    progress.clear()
    assert "\033" not in line.getvalue() and "50.0%" in line.getvalue()
    assert line.getvalue().endswith("\r")  # blanked over, back at the start


def test_decode_colours_a_windows_console_only_in_vt_mode(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from analyzer.commands.decode import use_color

    monkeypatch.delenv("NO_COLOR", raising=False)
    monkeypatch.setattr(sys, "platform", "win32")
    old = FakeConsole(0x3, accepts=False)
    monkeypatch.setattr("analyzer.ansi.WindowsConsole", lambda: old)
    assert not use_color("auto", Terminal())
    monkeypatch.setattr("analyzer.ansi.WindowsConsole", lambda: FakeConsole(0x3, accepts=True))
    assert use_color("auto", Terminal())


def test_redirected_output_is_utf8_whatever_the_code_page() -> None:
    redirected = io.TextIOWrapper(io.BytesIO(), encoding="cp1252")
    utf8_when_redirected(redirected)
    redirected.write("yaw 45° → 90°\n")
    redirected.flush()
    assert redirected.buffer.getvalue() == "yaw 45° → 90°\n".encode()  # type: ignore[attr-defined]


def coarse(step: float = 0.0156) -> Callable[[], float]:
    """``time.time`` as Windows before Python 3.13 gives it: in 15.6 ms steps."""
    return lambda: (time.time() // step) * step


def test_timestamps_keep_the_monotonic_clocks_resolution() -> None:
    clock = WallClock(wall=coarse())
    times = []
    for _ in range(50):
        times.append(clock())
        time.sleep(0.001)
    assert all(b > a for a, b in itertools.pairwise(times))
    assert abs(clock() - time.time()) < 0.05  # anchored to the wall clock


def test_live_chunks_a_few_milliseconds_apart_get_their_own_times(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from analyzer import wall_clock

    monkeypatch.setattr(time, "time", coarse())  # what a source would have read
    stamps = []
    for _ in range(5):
        stamps.append(wall_clock.now())
        time.sleep(0.002)
    assert len(set(stamps)) == 5
