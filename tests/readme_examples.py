"""The commands and shown outputs of the README and of the manual's Markdown pages
(``docs/**/*.md``), checked against the tool (and refreshed).

Every ``gimbal-analyzer ...`` line in an indented code block of a page must be a
command a shell runs as written (``shlex``: quotes closed, no bare ``&`` that would
cut a URL) and that ``gimbal-analyzer``'s own argument parser accepts. Blocks that run
and compare say so in an HTML comment before them (blank lines may come between)::

    <!-- check: run -->            the block's commands run and exit 0
    <!-- check: exact -->          stdout is the block's output, line for line
    <!-- check: lines -->          each output line shown appears in stdout
    <!-- check: parse (why) -->    parse only (needs hardware, a camera, a long run)
    <!-- check: real (tests/test_x.py) -->
                                   a real run against the simulator on a loopback port,
                                   which the test named runs and compares (the numbers
                                   that vary from run to run masked); parse only here

A block's command lines are those where ``gimbal-analyzer`` is followed by a command
name or an option (``$ `` in front is allowed); the rest is the output. A block
without command lines shows the output of the commands of the code block before it.
In an exact block ``...`` as a line skips any lines; inside a line it stands for any
text (in both modes). ``; before: COMMAND`` in the comment runs COMMAND first (a file
the example needs, e.g. ``<!-- check: lines; before: gimbal-analyzer convert
samples/flight-candump.log -o flight.mcap -->``). Commands run in-process in a scratch
folder that holds a copy of ``samples/``; ``| head -N`` after a command keeps its
first N lines.

``python -m tests.readme_examples --update`` rewrites the shown outputs that no longer
match from what the commands print now (exact blocks whole, other lines by their
closest line of output), for the new figures to be reviewed in ``git diff``; page paths
after it (``docs/howto/decode.md``) check or update only those pages. A marked exact
block that shows no output yet gets all of it.
"""

from __future__ import annotations

import contextlib
import difflib
import io
import os
import re
import shutil
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

from tests.readme_blocks import Block, parse_failures, read_blocks, shell_problems

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
DOCS = ROOT / "docs"


def documents() -> list[Path]:
    """The README and every Markdown page of the manual, in a steady order."""
    pages = sorted(p for p in DOCS.rglob("*.md") if "_build" not in p.parts)
    return [README, *pages]


def page_name(path: Path) -> str:
    """How messages name a page: ``README``, ``docs/howto/decode.md``."""
    return "README" if path == README else path.relative_to(ROOT).as_posix()


_HEAD = re.compile(r"^\|\s*head\s+-(?:n\s*)?(\d+)\s*$")


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
        return list(difflib.unified_diff(shown, actual, "shown", "now", lineterm="", n=1))
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
            missing.append(f"- shown:  {line}")
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


def check_blocks(
    lines: list[str], *, update: bool = False, name: str = "README"
) -> tuple[list[str], list[str]]:
    """Run and compare every marked block of a page: (failures in words, the page's
    lines, updated when ``update``)."""
    failures: list[str] = []
    lines = list(lines)
    blocks = read_blocks(lines, name)
    with scratch_folder():
        outputs: dict[int, list[str]] = {}  # block index -> stdout lines of its commands
        replacements: list[tuple[Block, list[str]]] = []
        for index, block in enumerate(blocks):
            if block.mode in (None, "parse", "real"):  # real: its own test runs it
                continue
            where = f"{name} line {block.start + 1} ({block.mode})"
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
                            f"{name} line {number}: {command} exited {code}: {err.strip()}"
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


def main(argv: list[str]) -> int:
    update = "--update" in argv
    chosen = [ROOT / arg for arg in argv if not arg.startswith("--")]
    failed = False
    for path in chosen or documents():
        name = page_name(path)
        lines = path.read_text(encoding="utf-8").splitlines()
        failures = parse_failures(lines, name)
        compared, new = check_blocks(lines, update=update, name=name)
        if update and new != lines:
            path.write_text("\n".join(new) + "\n", encoding="utf-8")
            print(f"updated {name} (review it with git diff)")
        for failure in failures + compared:
            print(failure, end="\n\n")
        failed = failed or bool(failures) or (bool(compared) and not update)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    sys.exit(main(sys.argv[1:]))
