"""Escape sequences from file content never reach the terminal raw; --raw notes fit --raw."""

from __future__ import annotations

import json
import unicodedata
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from analyzer.cli import main
from analyzer.terminal_text import printable

# An OSC that retitles the terminal, a colour change and a "clear screen".
HOSTILE = "\x1b]0;owned\x07\x1b[31m\x1b[2J"


def _raw_control(text: str) -> list[str]:
    """Characters a terminal would act on instead of showing (newlines between lines aside)."""
    return [
        c
        for line in text.split("\n")
        for c in line
        if unicodedata.category(c) == "Cc" or c in "\u2028\u2029\u202e\u2066"
    ]


def test_printable_escapes_controls_and_keeps_everything_else() -> None:
    assert printable("can0 gimbal_control 5 deg/s") == "can0 gimbal_control 5 deg/s"
    assert printable("é ü 中文 ✓") == "é ü 中文 ✓"
    assert printable(HOSTILE) == "\\x1b]0;owned\\x07\\x1b[31m\\x1b[2J"
    assert printable("a\nb\tc\rd\x7f\x9b") == "a\\nb\\tc\\rd\\x7f\\x9b"
    assert printable("abc\u202edef") == "abc\\u202edef"  # right-to-left override


@settings(max_examples=200)
@given(st.text())
def test_printable_output_never_holds_a_control_character(text: str) -> None:
    shown = printable(text)
    assert "\n" not in shown
    assert not _raw_control(shown)
    if not _raw_control(text) and "\n" not in text:
        assert shown == text


def _hostile_candump(path: Path) -> None:
    text = b"HI".hex() + HOSTILE.encode()[:6].hex()  # 8 bytes of text, ESC included
    path.write_text(
        f"(1715680800.010000) can{HOSTILE}0 00000F01#0F01000000000000\n"
        f"(1715680800.020000) can0 02008201#{text}\n"
        "(1715680800.030000) can0 02008202#21000000\n"
        f"(1715680800.040000) can{HOSTILE}1 030F0001#EB900C0000000000\n",
        encoding="utf-8",
    )


@pytest.mark.parametrize("extra", [[], ["--summary"], ["--raw"], ["--raw", "--summary"]])
def test_decode_escapes_channel_names_and_text_messages(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str]
) -> None:
    log = tmp_path / "hostile.log"
    _hostile_candump(log)
    assert main(["decode", str(log), "--color", "never", *extra]) == 0
    captured = capsys.readouterr()
    assert not _raw_control(captured.out), captured.out
    assert not _raw_control(captured.err), captured.err
    if "--summary" not in extra:
        assert "can\\x1b]0;owned\\x07" in captured.out
        assert "HI\\x1b" in captured.out


def test_decode_with_colour_escapes_the_input_but_keeps_its_own_colours(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "hostile.log"
    _hostile_candump(log)
    assert main(["decode", str(log), "--color", "always"]) == 0
    out = capsys.readouterr().out
    assert "\x1b[2J" not in out and "\x1b]0;" not in out and "\x07" not in out
    assert "can\\x1b]0;owned" in out
    assert "\x1b[0m" in out  # the analyzer's own styling is still there


def test_info_escapes_metadata_and_names_from_the_recording(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / f"flight{HOSTILE}.log"  # the path ends up in the recording's metadata
    _hostile_candump(log)
    recording = tmp_path / "hostile.mcap"
    assert main(["convert", str(log), "-o", str(recording), "-q"]) == 0
    capsys.readouterr()
    assert main(["info", str(recording)]) == 0
    out = capsys.readouterr().out
    assert not _raw_control(out), out
    assert "source      file:" in out and "flight\\x1b]0;owned\\x07" in out
    assert main(["info", str(recording), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)  # JSON keeps the exact text, escaped by JSON
    assert HOSTILE in data["metadata"]["source"]
    assert main(["decode", str(recording), "--summary"]) == 0
    captured = capsys.readouterr()
    assert not _raw_control(captured.out) and not _raw_control(captured.err)


def test_errors_escape_what_they_quote(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["decode", str(tmp_path / f"missing{HOSTILE}.log")]) == 2
    err = capsys.readouterr().err
    assert not _raw_control(err) and "missing\\x1b]0;owned" in err


def test_raw_summary_note_does_not_suggest_raw(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = tmp_path / "other.log"
    log.write_text(
        "(1715680800.010000) can0 12345678#00\n(1715680800.020000) can0 12345678#01\n",
        encoding="utf-8",
    )
    assert main(["decode", str(log), "--summary"]) == 0
    assert "(--raw shows them)" in capsys.readouterr().err
    assert main(["decode", str(log), "--raw", "--summary"]) == 0
    err = capsys.readouterr().err
    assert "--raw shows them" not in err
    assert "none of the 2 CAN frames uses a protocol ID" in err
    assert "they are the /can/other events" in err
