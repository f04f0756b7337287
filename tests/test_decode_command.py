"""`gimbal-analyzer decode`: output modes, filters, errors, colour, progress, live stdin."""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

import pytest

from analyzer.cli import main
from analyzer.commands.decode import Progress, event_filter, use_color
from analyzer.errors import UsageError
from analyzer.protocol.codec import encode_command
from analyzer.protocol.feedback import encode_attitude, segments
from analyzer.protocol.framing import wrap_control
from analyzer.protocol.types import Event

T0 = 1_700_000_000.0


def log_file(tmp_path: Path, extra: list[str] | None = None) -> Path:
    """A small candump -L log: two commands, one attitude message, other traffic, a bad line."""
    lines = [
        f"({T0:.6f}) can0 00000F01#{encode_command('gimbal_control', pan_speed_dps=-5.0, tilt_speed_dps=0).hex()}",
        f"({T0 + 0.1:.6f}) can0 18FEF100#0011223344556677",
        f"({T0 + 0.2:.6f}) can0 00000F01#{encode_command('look_down').hex()}",
        "this line is damaged",
    ]
    att = segments(encode_attitude(pitch_deg=-10.0, yaw_deg=100.0, motor_yaw_deg=5.0))
    lines += [f"({T0 + 0.5 + i / 1000:.6f}) can0 030F0001#{s.hex()}" for i, s in enumerate(att)]
    lines += extra or []
    path = tmp_path / "flight.log"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(["decode", *args])
    out, err = capsys.readouterr()
    return code, out, err


def test_text_output_one_line_per_event(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, str(log_file(tmp_path)))
    assert code == 0
    lines = out.splitlines()
    assert len(lines) == 4
    assert "gimbal_control   pan -5.00 deg/s  tilt 0.00 deg/s" in lines[0]
    assert "look_down" in lines[1]
    assert "BAD_LINE" in lines[2] and "line 4" in lines[2]
    assert "/gimbal/attitude" in lines[3] and "yaw 100.00 deg" in lines[3]
    assert "\033[" not in out  # not a terminal: no colour
    assert err == ""


def test_json_lines_follow_the_event_contract(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, out, _ = run(capsys, str(log_file(tmp_path)), "--json")
    assert code == 0
    objects = [json.loads(line) for line in out.splitlines()]
    assert [o["topic"] for o in objects] == [
        "/gimbal/command",
        "/gimbal/command",
        "/diagnostics",
        "/gimbal/attitude",
    ]
    for obj in objects:
        assert {"topic", "time", "source", "warnings"} <= obj.keys()
        assert Event.from_dict(obj).to_dict() == obj
    assert objects[0]["pan_speed_dps"] == -5.0 and objects[0]["time"] == T0
    assert objects[2]["kind"] == "bad_line" and objects[2]["line"] == 4


def test_summary_text(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, str(log_file(tmp_path)), "--summary")
    assert code == 0
    assert "Summary of" in out and "(candump)" in out
    assert "8 lines, 7 CAN frames (6 protocol, 1 other), 1 bad lines" in out
    assert "/gimbal/command" in out and "bad_line" in out
    assert "1 messages, rate unknown" in out
    assert "0 of 1 CRC-protected messages" in out


def test_summary_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, str(log_file(tmp_path)), "--summary", "--json")
    assert code == 0
    (obj,) = [json.loads(line) for line in out.splitlines()]
    assert obj["summary"] is True
    assert obj["topics"] == {"/diagnostics": 1, "/gimbal/attitude": 1, "/gimbal/command": 2}
    assert obj["diagnostics"] == 1
    assert obj["diagnostics_by_kind"] == {"bad_line": 1}
    # Frames with other IDs are counted once, under one name (the reader skipped this one).
    assert obj["decoder"]["other_frames"] == 1 and "other_frames" not in obj["input"]
    assert obj["time_base"] == "absolute"
    assert obj["first_time"] == T0


@pytest.mark.parametrize(
    ("args", "topics"),
    [
        (["--topic", "/gimbal/command"], ["/gimbal/command"] * 2),
        (["--topic", "/gimbal"], ["/gimbal/command"] * 2 + ["/gimbal/attitude"]),
        (["--topic", "gimbal"], ["/gimbal/command"] * 2 + ["/gimbal/attitude"]),
        (["--topic", "gimbal/command"], ["/gimbal/command"] * 2),
        (["--topic", "uav"], []),
        (["--topic", "diagnostics"], ["/diagnostics"]),
        (["--topic", "attitude,diagnostics"], ["/diagnostics", "/gimbal/attitude"]),
        (["--name", "look_down"], ["/gimbal/command"]),
        (["--name", "bad_line", "--name", "look_down"], ["/gimbal/command", "/diagnostics"]),
        (["--topic", "/uav"], []),
    ],
)
def test_filters(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], topics: list[str]
) -> None:
    code, out, _ = run(capsys, str(log_file(tmp_path)), "--json", *args)
    assert code == 0
    assert [json.loads(line)["topic"] for line in out.splitlines()] == topics


def test_an_unknown_topic_lists_the_topics_and_their_prefix_forms(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, _, err = run(capsys, str(log_file(tmp_path)), "--topic", "gimbals")
    assert code == 2
    assert "unknown topic 'gimbals'" in err
    assert "/gimbal/attitude" in err
    assert "a prefix (" in err and "/uav" in err and "without the /: gimbal, uav" in err


def test_raw_shows_other_frames(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _, out, _ = run(capsys, str(log_file(tmp_path)), "--raw", "--topic", "other")
    assert out.splitlines()[0].endswith("id 0x18FEF100 [8] 00 11 22 33 44 55 66 77")
    _, out, _ = run(capsys, str(log_file(tmp_path)))
    assert "/can/other" not in out


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["missing.log"], "no such file"),
        (["{dir}"], "directory"),
        (["{file}", "--format", "wav"], "unknown format"),
        (["{file}", "--topic", "/nope"], "unknown topic"),
        (["{file}", "--name", "warp_drive"], "unknown name"),
        (["{file}", "--port", "0"], "--port"),
        (["{notes}"], "cannot tell the format"),
    ],
)
def test_errors_are_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], words: str
) -> None:
    notes = tmp_path / "notes.txt"
    notes.write_text("not a capture\n", encoding="utf-8")
    values = {"dir": str(tmp_path), "file": str(log_file(tmp_path)), "notes": str(notes)}
    code, out, err = run(capsys, *[a.format(**values) for a in args])
    assert code == 2 and out == ""
    assert len(err.splitlines()) == 1 and words in err
    assert err.startswith("gimbal-analyzer decode: error: ")


def test_stream_dump_with_format_option(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "capture.dat"
    path.write_bytes(b"\x01\x02" + wrap_control(encode_command("look_down")))
    code, out, _ = run(capsys, str(path), "--format", "stream", "--json")
    assert code == 0
    kinds = [json.loads(line).get("kind") or json.loads(line)["name"] for line in out.splitlines()]
    assert kinds == ["garbage", "look_down"]


def test_stdin(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    line = f"(1.0) can0 00000F01#{encode_command('look_down').hex()}\n"
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(line.encode()), encoding="utf-8"))
    code, out, _ = run(capsys, "-", "--json")
    assert code == 0 and json.loads(out)["name"] == "look_down"


# -- colour and progress ---------------------------------------------------------------------


class FakeTty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_colour_choice(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("NO_COLOR", raising=False)
    assert use_color("auto", FakeTty()) is True
    assert use_color("auto", io.StringIO()) is False
    monkeypatch.setenv("NO_COLOR", "1")
    assert use_color("auto", FakeTty()) is False
    assert use_color("always", io.StringIO()) is True
    assert use_color("never", FakeTty()) is False


def test_colour_always(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _, out, _ = run(capsys, str(log_file(tmp_path)), "--color", "always")
    assert "\033[1;31mBAD_LINE" in out


class FakeReader:
    source = "big.log"
    size_bytes = 1000
    position_bytes = 250


def test_progress_only_on_a_terminal_not_used_by_the_events() -> None:
    assert Progress.maybe(FakeReader(), io.StringIO(), io.StringIO(), False) is None
    assert Progress.maybe(FakeReader(), FakeTty(), FakeTty(), False) is None
    assert Progress.maybe(FakeReader(), FakeTty(), FakeTty(), True) is not None
    err = FakeTty()
    progress = Progress.maybe(FakeReader(), err, io.StringIO(), False)
    assert progress is not None
    progress.update()
    progress.clear()
    text = err.getvalue()
    assert "big.log" in text and " 25.0%" in text and text.endswith("\r\033[K")


def test_no_progress_without_a_size() -> None:
    reader: Any = FakeReader()
    reader.size_bytes = None
    assert Progress.maybe(reader, FakeTty(), io.StringIO(), False) is None


def test_filter_none_without_options() -> None:
    assert event_filter([], []) is None
    with pytest.raises(UsageError):
        event_filter(["/"], [])


# -- the real program ------------------------------------------------------------------------


def test_live_pipe_prints_each_event_as_it_arrives(tmp_path: Path) -> None:
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])}
    proc = subprocess.Popen(
        [sys.executable, "-m", "analyzer", "decode", "-"],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env,
    )
    assert proc.stdin is not None and proc.stdout is not None
    try:
        line = f"(1.0) can0 00000F01#{encode_command('look_down').hex()}\n"
        proc.stdin.write(line.encode())
        proc.stdin.flush()
        got: list[bytes] = []
        stdout = proc.stdout
        reader = threading.Thread(target=lambda: got.append(stdout.readline()), daemon=True)
        reader.start()
        reader.join(timeout=30)
        assert got and b"look_down" in got[0], "no output while the pipe is still open"
        proc.stdin.write(b"(2.0) can0 00000F01#0F02000000000000\n")
        proc.stdin.close()
        rest = proc.stdout.read()
        assert proc.wait(timeout=30) == 0
        assert b"forward" in rest
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_ctrl_c_on_live_input_still_prints_the_summary(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    class Interrupting(io.RawIOBase):
        def __init__(self) -> None:
            self.lines = [f"(1.0) can0 00000F01#{encode_command('look_down').hex()}\n".encode()]

        def readable(self) -> bool:
            return True

        def readline(self, size: int | None = -1) -> bytes:
            if self.lines:
                return self.lines.pop()
            raise KeyboardInterrupt

    fake = io.TextIOWrapper(io.BufferedReader(Interrupting()), encoding="utf-8")
    fake.buffer.readline = fake.buffer.raw.readline  # type: ignore[method-assign]
    monkeypatch.setattr(sys, "stdin", fake)
    code, out, _ = run(capsys, "-", "--summary")
    assert code == 130
    assert "/gimbal/command" in out and "1 lines" in out


def test_wrong_port_says_which_ports_the_capture_has(capsys: pytest.CaptureFixture[str]) -> None:
    sample = Path(__file__).resolve().parent.parent / "samples" / "idu-tcp.pcap"
    assert main(["decode", str(sample), "--port", "2001"]) == 0
    captured = capsys.readouterr()
    assert captured.out == ""
    assert "no TCP traffic to or from port 2001" in captured.err
    assert "TCP ports seen: 2000 (" in captured.err
    assert main(["decode", str(sample)]) == 0
    assert "note:" not in capsys.readouterr().err


def test_a_log_without_protocol_frames_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "other-bus.log"
    path.write_text(
        f"({T0:.6f}) can0 18FEF100#0011\n({T0 + 1:.6f}) can0 123#01\n", encoding="utf-8"
    )
    assert main(["decode", str(path)]) == 0
    err = capsys.readouterr().err
    assert "none of the 2 CAN frames uses a protocol ID" in err
    assert main(["decode", str(log_file(tmp_path))]) == 0
    assert "note:" not in capsys.readouterr().err


def test_pcap_summary_names_the_port(capsys: pytest.CaptureFixture[str]) -> None:
    sample = Path(__file__).resolve().parents[1] / "samples" / "idu-tcp.pcap"
    code, out, _ = run(capsys, str(sample), "--summary")
    assert code == 0
    assert "TCP to/from port 2000," in out
    code, out, _ = run(capsys, str(sample), "--summary", "--port", "2001")
    assert "0 TCP to/from port 2001" in out
