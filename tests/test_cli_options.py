"""One meaning per option letter in every command, and argparse errors in one line."""

from __future__ import annotations

import argparse
from collections import defaultdict
from pathlib import Path

import pytest

from analyzer.cli import COMMANDS, build_parser, main
from analyzer.errors import EXIT_USAGE


def _options() -> dict[str, dict[str, tuple[str, ...]]]:
    """command -> option string -> every option string of the same option."""
    parser = build_parser()
    found: dict[str, dict[str, tuple[str, ...]]] = {}
    for name, command in parser.commands.items():
        found[name] = {
            option: tuple(action.option_strings)
            for action in command._actions
            for option in action.option_strings
        }
    return found


def test_every_command_has_its_parser() -> None:
    assert set(_options()) == set(COMMANDS)


def test_each_short_option_means_one_thing_in_every_command() -> None:
    meanings: dict[str, set[tuple[str, ...]]] = defaultdict(set)
    where: dict[tuple[str, tuple[str, ...]], list[str]] = defaultdict(list)
    for command, options in _options().items():
        for option, names in options.items():
            if not option.startswith("--"):
                longs = tuple(n for n in names if n.startswith("--"))
                meanings[option].add(longs)
                where[option, longs].append(command)
    mixed = {
        short: {longs: where[short, longs] for longs in found}
        for short, found in meanings.items()
        if len(found) > 1
    }
    assert mixed == {}
    assert meanings["-f"] == {("--force",)}  # as in cp and rm


def test_a_long_option_with_a_letter_has_it_everywhere() -> None:
    """--force is -f (and --output -o, --quiet -q) in every command that has it."""
    letters: dict[str, set[str]] = defaultdict(set)
    for options in _options().values():
        for names in options.values():
            shorts = {n for n in names if not n.startswith("--")}
            for name in names:
                if name.startswith("--") and name != "--help":
                    letters[name].add(min(shorts) if shorts else "")
    assert {name: found for name, found in letters.items() if len(found) > 1} == {}
    assert letters["--force"] == {"-f"} and letters["--format"] == {""}


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["decode", "x.log", "-f", "candump"],
            "gimbal-analyzer decode: error: unrecognized arguments: -f candump (-f is --force "
            "wherever it exists; the format is --format FORMAT; see: gimbal-analyzer decode --help)",
        ),
        (
            ["analyze", "x.log", "--tolerance", "abc"],
            "gimbal-analyzer analyze: error: argument --tolerance: 'abc' is not a number "
            "(see: gimbal-analyzer analyze --help)",
        ),
        (
            ["table", "-o", "fleet"],
            "gimbal-analyzer table: error: the following arguments are required: INPUT "
            "(see: gimbal-analyzer table --help)",
        ),
    ],
)
def test_usage_errors_are_one_line_with_a_hint(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == EXIT_USAGE
    captured = capsys.readouterr()
    assert captured.err == message + "\n" and captured.out == ""


def test_a_file_given_to_monitor_without_source_points_to_file_source(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "flight-candump.log").write_text("(1.0) can0 0F01#0F04\n", encoding="utf-8")
    for argv, spec in (
        (["monitor", "flight-candump.log"], "file:flight-candump.log"),
        (["record", "-o", "x.mcap"], "file:PATH"),
    ):
        with pytest.raises(SystemExit) as exit_info:
            main(argv)
        assert exit_info.value.code == EXIT_USAGE
        err = capsys.readouterr().err
        assert "required: --source" in err
        assert f"(a file is replayed with --source {spec}; see: gimbal-analyzer" in err


def test_report_takes_f_for_force(tmp_path: pytest.TempPathFactory) -> None:
    parser = build_parser("report")
    args = parser.parse_args(["report", "demo.mcap", "-o", "r.html", "-f"])
    assert args.force is True and args.format is None
    assert isinstance(parser, argparse.ArgumentParser)


def test_commands_lists_every_message_with_its_can_id(capsys: pytest.CaptureFixture[str]) -> None:
    """What its help promises: the commands, the feedback and the UAV status messages,
    from the same tables the decoder uses."""
    from analyzer.protocol.command_table import COMMANDS as TABLE
    from analyzer.protocol.feedback import LAYOUTS
    from analyzer.protocol.ids import PROTOCOL_IDS
    from analyzer.protocol.uav import STATUS_FRAMES

    assert main(["commands"]) == 0
    out = capsys.readouterr().out
    for can_id in PROTOCOL_IDS:
        assert f"0x{can_id:08X}" in out
    lines = out.splitlines()
    for row in TABLE:
        assert any(line.startswith(f"{row.name} ") for line in lines)
    for layout in LAYOUTS.values():
        head = f"{layout.name:<18} length byte 0x{layout.length_byte:02X}  {layout.topic}"
        assert any(line.startswith(head) for line in lines)
        assert all(f"    `{f.name}` byte {f.offset}" in out for f in layout.layout.fields)
    for status in STATUS_FRAMES.values():
        head = f"{status.name:<18} CAN ID 0x{status.can_id:08X}  {status.topic}"
        assert any(line.startswith(head) for line in lines)
        assert all(f"    `{f.name}` byte {f.offset}" in out for f in status.layout.fields)
    assert "text               CAN ID 0x02008201 start/middle, 0x02008202 end  /uav/text" in out
