"""A tutorial's prose quotes no figure that its checked output does not show.

The outputs of a tutorial's checked blocks (``exact`` and ``lines``; ``real``: a real run
that a test of its own compares) are compared with what the tool prints (``test_readme``);
the sentences around them are not. So each figure written in digits in a tutorial's prose
must appear in a checked output or a command line of the same page (the user's own
settings), unless it is one of the protocol's or the tool's documented constants below;
and a count written in words ("two messages") must be one the checked output shows for
that noun ("1 message lost" does not make two).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.readme_blocks import Block, read_blocks

TUTORIALS = sorted((Path(__file__).resolve().parent.parent / "docs" / "tutorials").glob("*.md"))
CHECKED = ("exact", "lines", "real")

# Figures that are the protocol's or the tool's constants, not measurements of a run.
CONSTANTS = (
    r"every 0\.5 s",  # the feedback period (chapter 3 of the protocol document)
    r"every 50 ms",  # the stick's gimbal_control period the document recommends
    r"for\s+10 s",  # demo: how long it runs without --duration
    r"1 Mbit/s",  # the gimbal's CAN bitrate
    r"exit code is 1",  # check: a step failed
    r"G-\d+",  # the example gimbals' names
)
NUMBER_WORDS = {
    "one": 1,
    "two": 2,
    "three": 3,
    "four": 4,
    "five": 5,
    "six": 6,
    "seven": 7,
    "eight": 8,
    "nine": 9,
    "ten": 10,
}
# Nouns an output counts; a count of one of these in words is held against the output.
COUNTED = ("message", "gap", "error", "row", "frame", "event", "command", "finding", "step")
FIGURE = re.compile(r"(?<![\w.-])\d[\d,]*(?:\.\d+)?(?![\w.])")
_COUNT_IN_WORDS = re.compile(
    r"\b(" + "|".join(NUMBER_WORDS) + r")\s+(?:[a-z-]+\s+)?(" + "|".join(COUNTED) + r")s?\b",
    re.IGNORECASE,
)
_COUNT_IN_DIGITS = re.compile(  # one space apart: a table's columns are two
    r"\b(\d[\d,]*) (?:[\w-]+ )?(" + "|".join(COUNTED) + r")s?\b", re.IGNORECASE
)
_INLINE_CODE = re.compile(r"`[^`]*`")


def prose(lines: list[str], blocks: list[Block]) -> tuple[str, list[str]]:
    """The page's lines that are no code block, marker or heading, and apart the inline
    code that gives a command or its options (the user's settings; other inline code, a
    line of output quoted, stays in the prose)."""
    inside = {b.start + i for b in blocks for i in range(len(b.lines))}
    text = "\n".join(
        line
        for index, line in enumerate(lines)
        if index not in inside and not line.startswith(("<!--", "#"))
    )
    settings = [code for code in _INLINE_CODE.findall(text) if _is_setting(code)]
    return _INLINE_CODE.sub(lambda m: " " if _is_setting(m.group(0)) else m.group(0), text), [
        code.strip("`") for code in settings
    ]


def _is_setting(code: str) -> bool:
    return code.strip("`").startswith(("-", "gimbal-analyzer"))


def shown(blocks: list[Block]) -> tuple[str, str]:
    """(what the checked outputs show, every command line) of a page's blocks."""
    outputs = [line for b in blocks if b.mode in CHECKED for line in b.output()]
    commands = [command for b in blocks for _, command in b.commands()]
    return "\n".join(outputs), "\n".join(commands)


def unshown_figures(text: str, output: str, commands: str) -> list[str]:
    """The figures of a piece of prose that neither the output nor a command holds."""
    for constant in CONSTANTS:
        text = re.sub(constant, " ", text)
    seen = set(FIGURE.findall(output)) | set(FIGURE.findall(commands))
    return [figure for figure in FIGURE.findall(text) if figure not in seen]


def counts_in_words_not_shown(text: str, output: str) -> list[str]:
    """Counts in words ("two gaps") of a noun the output counts, with another number."""
    counted: dict[str, set[int]] = {}
    for number, noun in _COUNT_IN_DIGITS.findall(output):
        counted.setdefault(noun.lower(), set()).add(int(number.replace(",", "")))
    wrong = []
    for found in _COUNT_IN_WORDS.finditer(text):
        number, noun = NUMBER_WORDS[found.group(1).lower()], found.group(2).lower()
        if noun in counted and number not in counted[noun]:
            wrong.append(f"{found.group(0)!r} (the output shows {sorted(counted[noun])})")
    return wrong


@pytest.mark.parametrize("page", TUTORIALS, ids=lambda p: p.name)
def test_the_prose_quotes_only_figures_the_checked_output_shows(page: Path) -> None:
    lines = page.read_text(encoding="utf-8").splitlines()
    blocks = read_blocks(lines, page.name)
    output, commands = shown(blocks)
    text, settings = prose(lines, blocks)
    commands += "\n" + "\n".join(settings)
    assert unshown_figures(text, output, commands) == [], page.name
    assert counts_in_words_not_shown(text, output) == [], page.name


def test_a_stale_figure_and_a_count_in_words_are_caught() -> None:
    output = "longest gap 1.000 s; 1 gap, 1 message lost\nCRC errors 1 of 39 messages"
    text = "here two messages were lost in two gaps, and one of the 39 messages (37.7 s)"
    assert unshown_figures(text, output, "") == ["37.7"]
    assert counts_in_words_not_shown(text, output) == [
        "'two messages' (the output shows [1, 39])",
        "'two gaps' (the output shows [1])",
    ]
    fixed = "here one message was lost in one gap, and one of the 39 messages"
    assert unshown_figures(fixed, output, "") == []
    assert counts_in_words_not_shown(fixed, output) == []
    assert unshown_figures("the feedback comes every 0.5 s", "", "") == []
