"""One table of exit codes, SIGTERM handled like Ctrl-C, one grammar for links."""

from __future__ import annotations

import os
import re
import shlex
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from analyzer.cli import COMMANDS, build_parser, main
from analyzer.errors import EXIT_CODES, EXIT_INTERRUPTED, EXIT_USAGE, UsageError
from tests.platforms import posix_signals

ROOT = Path(__file__).resolve().parents[1]
ENV = {**os.environ, "PYTHONPATH": str(ROOT)}
CANDUMP_LINE = "(1715680800.010000) can0 030F0000#0F01000000000000\n"


def test_the_manual_makes_its_exit_code_table_from_the_code() -> None:
    """The manual's table is generated from EXIT_CODES when it is built (tests/test_manual.py
    checks the built page), so it has no copy of its own to go stale."""
    text = (ROOT / "docs" / "reference" / "exit-codes.md").read_text(encoding="utf-8")
    assert "```{gimbal-exit-codes}" in text
    assert not re.search(r"^\| \d+ \|", text, re.MULTILINE)


def test_help_shows_the_exit_code_table(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        from analyzer.cli import build_parser

        build_parser().parse_args(["--help"])
    out = capsys.readouterr().out
    for code, _ in EXIT_CODES:
        assert re.search(rf"^  {code} ", out, re.MULTILINE)


def test_a_command_loads_only_its_own_module(tmp_path: Path) -> None:
    log = tmp_path / "x.log"
    log.write_text(CANDUMP_LINE, encoding="utf-8")
    code = (
        "import sys; from analyzer.cli import main; "
        f"main(['--local-time', 'decode', '--summary', {str(log)!r}]); "
        "print(sorted(m for m in sys.modules if m.startswith('analyzer.commands.')))"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env=ENV,
        check=True,
        encoding="utf-8",
    )
    assert proc.stdout.splitlines()[-1] == "['analyzer.commands.decode']"


def test_unknown_command_still_lists_every_command(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["no-such-command"])
    assert exit_info.value.code == EXIT_USAGE
    err = capsys.readouterr().err
    assert "invalid choice" in err and "'simulate'" in err and "'decode'" in err


def test_unreadable_mcap_input_is_exit_2_in_every_command(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    empty = tmp_path / "empty.mcap"
    empty.write_bytes(b"")
    not_mcap = tmp_path / "text.mcap"
    not_mcap.write_text("hello\n", encoding="utf-8")
    for path in (empty, not_mcap):
        for args in (
            ["info", str(path)],
            ["decode", str(path)],
            ["convert", str(path), "-o", str(tmp_path / "out.mcap")],
        ):
            code = main(args)
            err = capsys.readouterr().err
            assert code == EXIT_USAGE, (args, err)
            assert "error:" in err and "Traceback" not in err
    assert not (tmp_path / "out.mcap").exists()


@posix_signals
def test_sigterm_during_convert_removes_the_partial_output_and_says_so(tmp_path: Path) -> None:
    out = tmp_path / "out.mcap"
    proc = subprocess.Popen(
        [sys.executable, "-m", "analyzer", "convert", "-", "-o", str(out), "-q"],
        stdin=subprocess.PIPE,
        stderr=subprocess.PIPE,
        cwd=tmp_path,
        env=ENV,
    )
    assert proc.stdin is not None and proc.stderr is not None
    proc.stdin.write(CANDUMP_LINE.encode() * 100)
    proc.stdin.flush()
    deadline = time.monotonic() + 30
    while not any(p.name != "out.mcap" for p in tmp_path.iterdir()):  # the temporary file
        assert time.monotonic() < deadline and proc.poll() is None
        time.sleep(0.02)
    proc.send_signal(signal.SIGTERM)  # stdin stays open: convert is waiting for more input
    code = proc.wait(timeout=30)
    err = proc.stderr.read().decode()
    proc.stdin.close()
    assert code == EXIT_INTERRUPTED, err
    assert "Traceback" not in err
    assert "interrupted (SIGTERM)" in err and "was not written" in err
    left = list(tmp_path.iterdir())
    assert left == [], (left, err)  # neither the output nor a partial file


@pytest.mark.parametrize(
    ("text", "host", "port"),
    [
        ("tcp:2000", "127.0.0.1", 2000),
        ("tcp:5555", "127.0.0.1", 5555),
        ("tcp:127.0.0.1:2001", "127.0.0.1", 2001),
        ("tcp:idu.local", "idu.local", 2000),
        ("tcp:[::1]:2002", "::1", 2002),
    ],
)
def test_one_tcp_grammar_for_source_to_and_on(text: str, host: str, port: int) -> None:
    from analyzer.sim.transports import parse_link
    from analyzer.sources.spec import TcpSpec, parse_source

    assert parse_source(text) == TcpSpec(host, port)  # --source
    link = parse_link(text)  # --to (send) and --on (simulate)
    assert (link.host, link.port) == (host, port)


def test_tcp_alone_is_the_idu_for_sources_and_refused_for_sending() -> None:
    from analyzer.sim.transports import parse_link
    from analyzer.sources.spec import TcpSpec, parse_source

    assert parse_source("tcp:") == TcpSpec("192.168.42.200", 2000)
    with pytest.raises(UsageError):
        parse_link("tcp:")


def test_the_idu_side_of_a_proxy_follows_the_tcp_grammar() -> None:
    from analyzer.sources.spec import ProxySpec, parse_source

    assert parse_source("proxy:127.0.0.1:9000->2000") == ProxySpec(
        "127.0.0.1", 9000, "127.0.0.1", 2000
    )
    assert parse_source("proxy:9000->idu.local") == ProxySpec("0.0.0.0", 9000, "idu.local", 2000)


def _record_a_proxy(spec: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> str:
    out = tmp_path / "proxy.mcap"
    main(["record", "--source", spec, "-o", str(out), "--duration", "0.3", "-q"])
    return capsys.readouterr().err


def test_a_proxy_on_all_interfaces_says_so_with_its_address(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Listens only (port 0: any free port); nothing is sent anywhere.
    err = _record_a_proxy("proxy:0->127.0.0.1:9", tmp_path, capsys)
    match = re.search(r"listening on all interfaces \(0\.0\.0\.0:(\d+)\)", err)
    assert match and int(match.group(1)) > 0, err
    assert "reachable from other machines" in err
    assert f"proxy:127.0.0.1:{match.group(1)}->127.0.0.1:9 keeps it on this one" in err


def test_a_loopback_proxy_says_where_it_listens(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    err = _record_a_proxy("proxy:127.0.0.1:0->127.0.0.1:9", tmp_path, capsys)
    assert re.search(r"listening on 127\.0\.0\.1:\d+ for the ground station", err), err
    assert "all interfaces" not in err


def test_send_help_says_the_repeat_unit_is_required(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        main(["send", "gimbal_control", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert "the unit is required: 50ms or 0.5s" in out


def test_a_live_record_that_received_nothing_is_exit_1(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from analyzer.mcapio.read.reader import McapRecording

    probe = socket.create_server(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()  # nothing listens there: the client keeps retrying
    out = tmp_path / "empty.mcap"
    code = main(["record", "--source", f"tcp:{port}", "-o", str(out), "--duration", "0.3", "-q"])
    err = capsys.readouterr().err
    assert code == 1, err
    assert f"nothing was received from tcp:127.0.0.1:{port}" in err
    assert not McapRecording(out).recovered  # finished all the same, with its link diagnostics


@posix_signals
def test_a_signal_during_a_critical_step_takes_effect_after_it() -> None:
    from analyzer.errors import Terminated
    from analyzer.stdio import interrupts_deferred

    done: list[str] = []
    with pytest.raises(Terminated), interrupts_deferred():
        os.kill(os.getpid(), signal.SIGTERM)
        done.append("the step finished")
    assert done == ["the step finished"]


def help_examples() -> list[tuple[str, str]]:
    """(command, example line) of every ``gimbal-analyzer ...`` line in a --help text."""
    parser = build_parser()
    found = []
    for name, command in getattr(parser, "commands", {}).items():
        text = f"{command.description or ''}\n{command.epilog or ''}".replace("\\\n", " ")
        for line in text.splitlines():
            at = line.find("gimbal-analyzer ")
            if at >= 0 and line[:at].strip() in ("", "$"):
                # what follows two spaces is the example's explanation
                found.append((name, re.split(r"\s{2,}", line[at:].strip())[0]))
    return found


def test_every_help_example_pastes_into_a_shell_as_written() -> None:
    """An example pasted into bash runs the command it shows: no unquoted > or < that
    makes a file of an address and cuts the argument there, no bare &."""
    examples = help_examples()
    assert len(examples) > 30
    for name, example in examples:
        lexer = shlex.shlex(example, posix=True, punctuation_chars=True)
        lexer.whitespace_split = True
        tokens = list(lexer)
        bad = [t for t in tokens if t and set(t) <= set("<>&;") and t not in (";",)]
        assert not bad, f"gimbal-analyzer {name} --help: {example!r} holds {bad}"


MAX_HELP_COLUMNS = 100  # the manual's CLI reference shows --help laid out for 88 columns


@pytest.mark.parametrize("command", ["", *COMMANDS])
def test_no_help_line_runs_off_the_page(
    command: str, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The exit-code table and an option group's words (--video's camera video) are
    wrapped as argparse wraps the rest, for the terminal and the manual's reference."""
    monkeypatch.setenv("COLUMNS", "88")
    with pytest.raises(SystemExit):
        main([command, "--help"] if command else ["--help"])
    long = [line for line in capsys.readouterr().out.splitlines() if len(line) > MAX_HELP_COLUMNS]
    assert long == []
