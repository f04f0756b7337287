"""The README's commands and shown outputs, checked against the tool (and refreshed).

Every ``gimbal-analyzer ...`` line in an indented code block of README.md must be a
command a shell runs as written (``shlex``: quotes closed, no bare ``&`` that would
cut a URL) and that ``gimbal-analyzer``'s own argument parser accepts. Blocks that run
and compare say so in an HTML comment before them (blank lines may come between)::

    <!-- check: run -->            the block's commands run and exit 0
    <!-- check: exact -->          stdout is the block's output, line for line
    <!-- check: lines -->          each output line shown appears in stdout
    <!-- check: parse (why) -->    parse only (needs hardware, a camera, a long run)

A block's command lines are those starting with ``gimbal-analyzer`` or ``$ ``; the rest
is the output. A block without command lines shows the output of the commands of the
code block before it. In an exact block ``...`` as a line skips any lines; inside a
line it stands for any text (in both modes). ``; before: COMMAND`` in the comment runs COMMAND first (a file the example
needs, e.g. ``<!-- check: lines; before: gimbal-analyzer convert samples/flight-candump.log
-o flight.mcap -->``). Commands run in-process in a scratch folder that holds a copy
of ``samples/``; ``| head -N`` after a command keeps its first N lines.

``python -m tests.readme_examples --update`` rewrites the shown outputs that no longer
match from what the commands print now (exact blocks whole, other lines by their
closest line of output), for the new figures to be reviewed in ``git diff``.
"""

from __future__ import annotations

import contextlib
import difflib
import io
import os
import re
import shlex
import shutil
import sys
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
PROGRAMS = ("gimbal-analyzer",)
MODES = ("run", "exact", "lines", "parse")
_MARKER = re.compile(r"^<!--\s*check:\s*(.*?)\s*-->\s*$")
_HEAD = re.compile(r"^\|\s*head\s+-(?:n\s*)?(\d+)\s*$")


@dataclass
class Block:
    """An indented code block: its README lines (``start`` is the 0-based index of the
    first), the check asked for and the command lines it holds."""

    start: int
    lines: list[str]
    mode: str | None = None
    before: list[str] = field(default_factory=list)

    @property
    def text(self) -> list[str]:
        return [line[4:] for line in self.lines]

    def commands(self) -> list[tuple[int, str]]:
        """(README line number, command text) of the command lines, continuations joined."""
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


def read_blocks(lines: list[str]) -> list[Block]:
    """The indented code blocks of the README, with the check their marker asks for."""
    blocks: list[Block] = []
    marker: tuple[str, list[str]] | None = None
    index = 0
    while index < len(lines):
        line = lines[index]
        found = _MARKER.match(line)
        if found:
            marker = _parse_marker(found.group(1), index + 1)
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
            mode, before = marker if marker else (None, [])
            blocks.append(Block(start, body, mode, before))
            marker = None
            continue
        if line.strip():  # prose between a marker and a block: the marker is for none
            marker = None
        index += 1
    return blocks


def _parse_marker(text: str, number: int) -> tuple[str, list[str]]:
    parts = [part.strip() for part in text.split(";")]
    mode = parts[0].split(" ", 1)[0]  # the words after it are a comment: why, for readers
    if mode not in MODES:
        raise ValueError(f"README line {number}: unknown check {mode!r} (one of {MODES})")
    before = []
    for part in parts[1:]:
        key, _, value = part.partition(":")
        if key.strip() != "before" or not value.strip():
            raise ValueError(f"README line {number}: expected '; before: COMMAND', got {part!r}")
        before.append(value.strip())
    return mode, before


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


# -- running and comparing -------------------------------------------------------------------


def run(command: str) -> tuple[int, str, str]:
    """Run a README command line in this process: (exit code, stdout, stderr)."""
    from analyzer.cli import main

    head = None
    if "|" in command:
        command, _, rest = command.partition("|")
        found = _HEAD.match("|" + rest.strip())
        if not found:
            raise ValueError(f"only '| head -N' can follow a command that is run: {command}")
        head = int(found.group(1))
    (argv,), problems = shell_problems(command)
    if problems:
        raise ValueError(problems[0])
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as exc:  # --help, --version, a usage error: argparse exits
            code = exc.code if isinstance(exc.code, int) else 0 if exc.code is None else 2
    text = out.getvalue()
    if head is not None:
        text = "".join(text.splitlines(keepends=True)[:head])
    return code, text, err.getvalue()


def _pattern(line: str) -> re.Pattern[str]:
    return re.compile(".*".join(re.escape(piece) for piece in line.split("...")) + r"\Z")


def compare(mode: str, shown: list[str], actual: list[str]) -> list[str]:
    """What differs between the output shown and the actual one (empty: they agree)."""
    actual = [line.rstrip() for line in actual]
    while actual and not actual[-1]:
        actual.pop()
    if mode == "exact" and not any("..." in line for line in shown):
        if shown == actual:
            return []
        return list(difflib.unified_diff(shown, actual, "README", "now", lineterm="", n=1))
    missing = []
    at = 0
    skipping = False
    for line in shown:
        if line.strip() == "...":
            skipping = True
            continue
        pattern = _pattern(line)
        if mode == "lines":  # anywhere: a block may show lines of several commands
            found = next((i for i, text in enumerate(actual) if pattern.match(text)), None)
            if found is not None:
                continue
        elif skipping:
            found = next((i for i in range(at, len(actual)) if pattern.match(actual[i])), None)
        else:
            found = at if at < len(actual) and pattern.match(actual[at]) else None
        if found is None and mode == "exact" and not skipping:
            # Lines printed that the README does not show, before this one?
            later = next((i for i in range(at, len(actual)) if pattern.match(actual[i])), None)
            if later is not None:
                missing += [f"+ now:    {extra}  (not shown)" for extra in actual[at:later]]
                found = later
        skipping = False
        if found is None:
            closest = difflib.get_close_matches(line, actual[at:], n=1, cutoff=0.5)
            missing.append(f"- README: {line}")
            missing.append(f"+ now:    {closest[0]}" if closest else "+ now:    (no such line)")
            continue
        at = found + 1
    if mode == "exact" and not skipping and at < len(actual):
        missing += [f"+ now:    {extra}  (not shown)" for extra in actual[at:]]
    return missing


def updated(mode: str, shown: list[str], actual: list[str]) -> list[str]:
    """The shown output refreshed from ``actual``: an exact block without ``...`` is
    replaced whole; otherwise each line that matches nothing becomes its closest line."""
    actual = [line.rstrip() for line in actual]
    while actual and not actual[-1]:
        actual.pop()
    if mode == "exact" and not any("..." in line for line in shown):
        return actual
    out = []
    for line in shown:
        if line.strip() == "..." or any(_pattern(line).match(a) for a in actual):
            out.append(line)
            continue
        closest = difflib.get_close_matches(line, actual, n=1, cutoff=0.5)
        out.append(closest[0] if closest else line)
    return out


@contextlib.contextmanager
def scratch_folder() -> Iterator[Path]:
    """A temporary working folder with a copy of samples/ (commands write files there)."""
    with tempfile.TemporaryDirectory(prefix="readme-") as name:
        folder = Path(name)
        shutil.copytree(ROOT / "samples", folder / "samples")
        previous = Path.cwd()
        os.chdir(folder)
        try:
            yield folder
        finally:
            os.chdir(previous)


def check_blocks(lines: list[str], *, update: bool = False) -> tuple[list[str], list[str]]:
    """Run and compare every marked block: (failures in words, README lines, updated
    when ``update``)."""
    failures: list[str] = []
    lines = list(lines)
    blocks = read_blocks(lines)
    with scratch_folder():
        outputs: dict[int, list[str]] = {}  # block index -> stdout lines of its commands
        replacements: list[tuple[Block, list[str]]] = []
        for index, block in enumerate(blocks):
            if block.mode in (None, "parse"):
                continue
            where = f"README line {block.start + 1} ({block.mode})"
            for command in block.before:
                code, _, err = run(command)
                if code:
                    failures.append(f"{where}: before: {command} exited {code}: {err.strip()}")
            commands = block.commands()
            source = block
            if not commands and index > 0:
                source = blocks[index - 1]
                commands = source.commands()
            if not commands:
                failures.append(f"{where}: no command to run in it or in the block before")
                continue
            if source is block or index - 1 not in outputs:
                stdout: list[str] = []
                for number, command in commands:
                    code, out, err = run(command)
                    if code:
                        failures.append(
                            f"README line {number}: {command} exited {code}: {err.strip()}"
                        )
                    stdout += out.splitlines()
                outputs[index] = stdout
            else:
                outputs[index] = outputs[index - 1]
            if block.mode == "run":
                continue
            shown = block.output()
            differences = compare(block.mode, shown, outputs[index])
            if not differences:
                continue
            failures.append(
                f"{where}: the output shown is not what it prints now:\n" + "\n".join(differences)
            )
            if update:
                replacements.append((block, updated(block.mode, shown, outputs[index])))
    for block, new in reversed(replacements):  # from the end: earlier blocks keep their place
        _replace_output(lines, block, new)
    return failures, lines


def _replace_output(lines: list[str], block: Block, new: list[str]) -> None:
    """Put ``new`` in place of the output lines of ``block`` in ``lines``."""
    where = block.output_indices()
    first, last = (where[0], where[-1] + 1) if where else (len(block.lines), len(block.lines))
    lines[block.start + first : block.start + last] = ["    " + line for line in new]


def parse_failures(lines: list[str]) -> list[str]:
    """Every command line of every code block: shell quoting, then our parser."""
    failures = []
    for block in read_blocks(lines):
        for number, command in block.commands():
            calls, problems = shell_problems(command)
            for problem in problems:
                failures.append(f"README line {number}: {command}\n  {problem}")
            for argv in calls:
                if any(word.startswith("[") for word in argv):
                    continue  # a synopsis (options in brackets), not a command line
                problem = parse_problem(argv)
                if problem:
                    failures.append(f"README line {number}: {command}\n  {problem}")
    return failures


def main(argv: list[str]) -> int:
    lines = README.read_text(encoding="utf-8").splitlines()
    failures = parse_failures(lines)
    compared, new = check_blocks(lines, update="--update" in argv)
    if "--update" in argv and new != lines:
        README.write_text("\n".join(new) + "\n", encoding="utf-8")
        print(f"updated {README} (review it with git diff)")
    for failure in failures + compared:
        print(failure, end="\n\n")
    return 1 if failures or (compared and "--update" not in argv) else 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    sys.exit(main(sys.argv[1:]))
