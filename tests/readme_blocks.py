"""The code blocks of the README and the manual's pages as the docs test sees them:
markers, command lines and the output shown, and whether a command line is quoted right
and parses with our parser (the marker syntax is described in
``tests/readme_examples.py``)."""

from __future__ import annotations

import contextlib
import io
import re
import shlex
from dataclasses import dataclass, field

PROGRAMS = ("gimbal-analyzer",)
MODES = ("run", "exact", "lines", "parse", "real")
_MARKER = re.compile(r"^<!--\s*check:\s*(.*?)\s*-->\s*$")


@dataclass
class Block:
    """An indented code block: its lines in the page (``start`` is the 0-based index of
    the first), the check asked for (and the words after it: ``note``) and the command
    lines it holds."""

    start: int
    lines: list[str]
    mode: str | None = None
    before: list[str] = field(default_factory=list)
    note: str = ""

    @property
    def text(self) -> list[str]:
        return [line[4:] for line in self.lines]

    def commands(self) -> list[tuple[int, str]]:
        """(line number in the page, command text) of the command lines, continuations
        joined."""
        out: list[tuple[int, str]] = []
        pending = ""
        first = 0
        for index, line in enumerate(self.text):
            if not pending:
                stripped = line.strip()
                if stripped.startswith("$ "):
                    stripped = stripped[2:]
                if not _is_command(stripped):
                    continue
                pending, first = stripped, self.start + index + 1
            else:
                pending += "\n" + line.strip()
            if pending.endswith("\\"):
                pending = pending[:-1].rstrip() + " "
                continue
            if _unclosed(pending):
                continue
            out.append((first, pending))
            pending = ""
        if pending:
            out.append((first, pending))
        return out

    def output(self) -> list[str]:
        """The lines shown as output (everything that is no command line)."""
        return [self.text[i].rstrip() for i in self.output_indices()]

    def output_indices(self) -> list[int]:
        """Where the output lines are in ``text`` (blank lines around them left out)."""
        commands = {number for number, _ in self.commands()}
        shown: list[int] = []
        skip = 0
        for index in range(len(self.text)):
            if self.start + index + 1 in commands:
                skip = _command_length(self, index)
            if skip:
                skip -= 1
                continue
            shown.append(index)
        while shown and not self.text[shown[-1]].strip():
            shown.pop()
        while shown and not self.text[shown[0]].strip():
            shown.pop(0)
        return shown


def _is_command(text: str) -> bool:
    words = text.split()
    if "gimbal-analyzer" not in words:
        return False
    from analyzer.cli import COMMANDS

    at = words.index("gimbal-analyzer")
    # "gimbal-analyzer decode: error: ..." or "gimbal-analyzer 1.0" is output shown.
    after = words[at + 1] if len(words) > at + 1 else ""
    return not after or after in COMMANDS or after.startswith("-")


def _unclosed(text: str) -> bool:
    try:
        shlex.split(text, comments=True)
    except ValueError:
        return True
    return False


def _command_length(block: Block, index: int) -> int:
    """How many block lines the command starting at ``index`` takes."""
    text = block.text
    length = 1
    joined = text[index]
    while index + length < len(text) and (joined.endswith("\\") or _unclosed(joined)):
        joined += "\n" + text[index + length]
        length += 1
    return length


def read_blocks(lines: list[str], name: str = "README") -> list[Block]:
    """The indented code blocks of a page (``name`` in messages), with the check their
    marker asks for."""
    blocks: list[Block] = []
    marker: tuple[str, str, list[str]] | None = None
    index = 0
    while index < len(lines):
        line = lines[index]
        found = _MARKER.match(line)
        if found:
            marker = _parse_marker(found.group(1), f"{name} line {index + 1}")
            index += 1
            continue
        previous_blank = (
            index == 0 or not lines[index - 1].strip() or _MARKER.match(lines[index - 1])
        )
        if line.startswith("    ") and line.strip() and previous_blank:
            start = index
            while index < len(lines) and (
                lines[index].startswith("    ") or not lines[index].strip()
            ):
                index += 1
            body = lines[start:index]
            while body and not body[-1].strip():
                body.pop()
            mode, note, before = marker if marker else (None, "", [])
            blocks.append(Block(start, body, mode, before, note))
            marker = None
            continue
        if line.strip():  # prose between a marker and a block: the marker is for none
            marker = None
        index += 1
    return blocks


def _parse_marker(text: str, where: str) -> tuple[str, str, list[str]]:
    parts = [part.strip() for part in text.split(";")]
    mode, _, note = parts[0].partition(" ")  # the words after it are a comment: why, for readers
    if mode not in MODES:
        raise ValueError(f"{where}: unknown check {mode!r} (one of {MODES})")
    before = []
    for part in parts[1:]:
        key, _, value = part.partition(":")
        if key.strip() != "before" or not value.strip():
            raise ValueError(f"{where}: expected '; before: COMMAND', got {part!r}")
        before.append(value.strip())
    return mode, note.strip(), before


# -- shell words and our own parser --------------------------------------------------------


def shell_problems(command: str) -> tuple[list[list[str]], list[str]]:
    """The gimbal-analyzer argument lists of a command line as a shell splits it, and
    what is wrong with its quoting."""
    try:
        lexer = shlex.shlex(command, posix=True, punctuation_chars=True)
        lexer.whitespace_split = True
        tokens = list(lexer)
    except ValueError as exc:
        return [], [f"the shell cannot split it: {exc}"]
    problems = []
    if "&" in tokens:
        problems.append("a bare & runs the command in the background and cuts the argument there")
    calls: list[list[str]] = []
    current: list[str] | None = None
    for token in tokens:
        if token and set(token) <= set("();<>|&"):
            if current is not None:
                calls.append(current)
            current = None
            continue
        if current is not None:
            current.append(token)
        elif token in PROGRAMS:
            current = []
    if current is not None:
        calls.append(current)
    return calls, problems


def parse_problem(argv: list[str]) -> str | None:
    """What gimbal-analyzer's argument parser says about ``argv`` (None: it parses)."""
    from analyzer.cli import build_parser

    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            build_parser(argv[0] if argv else None).parse_args(argv)
    except SystemExit as exc:
        if exc.code not in (0, None):
            lines = err.getvalue().strip().splitlines()
            return lines[-1] if lines else f"exit {exc.code}"
    return None


def parse_failures(lines: list[str], name: str = "README") -> list[str]:
    """Every command line of every code block of a page: shell quoting, then our parser."""
    failures = []
    for block in read_blocks(lines, name):
        for number, command in block.commands():
            calls, problems = shell_problems(command)
            for problem in problems:
                failures.append(f"{name} line {number}: {command}\n  {problem}")
            for argv in calls:
                if any(word.startswith("[") for word in argv):
                    continue  # a synopsis (options in brackets), not a command line
                problem = parse_problem(argv)
                if problem:
                    failures.append(f"{name} line {number}: {command}\n  {problem}")
    return failures
