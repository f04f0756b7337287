"""The commands shown in the README and in the manual's pages parse with our own parser,
and the outputs they show are what the commands print."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.readme_blocks import parse_failures, read_blocks
from tests.readme_examples import ROOT, check_blocks, compare, documents, page_name, updated

HINT = "\n\nrefresh the shown outputs with: python -m tests.readme_examples --update"
PAGES = documents()


def _lines(path: Path) -> list[str]:
    return path.read_text(encoding="utf-8").splitlines()


@pytest.mark.parametrize("page", PAGES, ids=page_name)
def test_every_command_line_of_the_page_is_quoted_right_and_parses(page: Path) -> None:
    failures = parse_failures(_lines(page), page_name(page))
    assert not failures, "\n".join(failures)


@pytest.mark.parametrize("page", PAGES, ids=page_name)
def test_the_outputs_the_page_shows_are_what_the_commands_print(page: Path) -> None:
    failures, _ = check_blocks(_lines(page), name=page_name(page))
    assert not failures, "\n\n".join(failures) + HINT


def test_the_manual_is_checked_page_by_page_and_marks_outputs_of_every_kind() -> None:
    assert len(PAGES) > 20 and PAGES[0].name == "README.md"
    modes = {block.mode for page in PAGES for block in read_blocks(_lines(page))}
    assert {"run", "exact", "lines", "parse", "real"} <= modes


def test_a_real_run_shown_names_the_test_that_runs_and_compares_it() -> None:
    """A ``real`` block is not run by ``check_blocks``: the test its marker names must
    exist and name the page."""
    for page in PAGES:
        for block in read_blocks(_lines(page), page_name(page)):
            if block.mode != "real":
                continue
            where = f"{page_name(page)} line {block.start + 1}"
            named = ROOT / block.note.strip("()")
            assert named.parent.name == "tests" and named.is_file(), f"{where}: no {named}"
            source = named.read_text(encoding="utf-8")
            assert page.relative_to(ROOT).as_posix() in source, f"{where}: {named} does not name it"


# -- the checker itself ----------------------------------------------------------------------

STALE = """\
Some prose.

<!-- check: parse (needs a camera) -->

    gimbal-analyzer demo --video bench=rtsp://h/cam?channel=1&subtype=1
    gimbal-analyzer decode x.log --no-such-option
    gimbal-analyzer decode FILE [--format F]
    gimbal-analyzer fleet fleet --sql "SELECT 1
        FROM t"
    gimbal-analyzer decode: error: a shown error message, not a command
""".splitlines()


def test_a_bare_ampersand_and_a_stale_option_are_caught_but_not_a_synopsis() -> None:
    failures = parse_failures(STALE)
    assert len(failures) == 2
    assert "README line 5" in failures[0] and "bare &" in failures[0]
    assert (
        "README line 6" in failures[1] and "unrecognized arguments: --no-such-option" in failures[1]
    )


def test_a_marker_applies_to_the_next_block_only() -> None:
    lines = ["<!-- check: lines -->", "", "    gimbal-analyzer --version", "", "prose", "", "    x"]
    first, second = read_blocks(lines)
    assert (first.mode, second.mode) == ("lines", None)
    with pytest.raises(ValueError, match="unknown check 'exactly'"):
        read_blocks(["<!-- check: exactly -->", "", "    x"])


@pytest.mark.parametrize(
    ("mode", "shown", "actual", "agree"),
    [
        ("exact", ["a", "b"], ["a", "b", ""], True),
        ("exact", ["a", "c"], ["a", "b", "c"], False),  # b printed, not shown
        ("exact", ["a", "...", "d"], ["a", "b", "c", "d"], True),
        ("exact", ["a", "...", "d"], ["a", "b", "c", "d", "e"], False),
        ("exact", ["a b ..."], ["a b c d"], True),  # ... inside a line is any text
        ("lines", ["d", "b x..."], ["a", "b x y", "c", "d"], True),  # in any order
        ("lines", ["verdicts: 2"], ["verdicts: 3"], False),
    ],
)
def test_compare(mode: str, shown: list[str], actual: list[str], agree: bool) -> None:
    assert (compare(mode, shown, actual) == []) is agree


def test_update_replaces_a_stale_line_by_its_closest_line_of_output() -> None:
    shown = ["...", "verdicts: 4 obeyed, 2 not obeyed"]
    actual = ["x", "verdicts: 3 obeyed, 3 not obeyed", "y"]
    assert updated("lines", shown, actual) == ["...", "verdicts: 3 obeyed, 3 not obeyed"]
    assert updated("exact", ["a"], ["b", "c"]) == ["b", "c"]


def test_update_rewrites_every_stale_block_in_its_place() -> None:
    lines = [
        "<!-- check: exact -->",
        "",
        "    $ gimbal-analyzer --version",
        "    gimbal-analyzer 0.0",
        "    an old line",
        "",
        "prose",
        "",
        "<!-- check: lines -->",
        "",
        "    gimbal-analyzer --version",
        "    gimbal-analyzer 0.0.9",
    ]
    failures, new = check_blocks(lines, update=True)
    assert len(failures) == 2
    from analyzer import __version__

    now = f"    gimbal-analyzer {__version__}"
    assert new == [*lines[:3], now, *lines[5:11], now]
    assert check_blocks(new)[0] == []


def test_the_readme_is_a_short_front_door_with_the_two_commands_first() -> None:
    lines = PAGES[0].read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 200, f"README.md has {len(lines)} lines; the rest goes in docs/"
    assert lines[2:4] == [
        "    pip install . && gimbal-analyzer demo",
        "    pip install '.[test]' && python -m pytest -m \"not slow\" -n 2 --dist loadfile"
        " && python -m pytest -m slow",
    ]
