"""``import analyzer`` as integrators use it: the public names, a cheap import, the examples
of the docstrings and of docs/howto/python-api.md run, and a user's script that passes ``mypy --strict``."""

from __future__ import annotations

import doctest
import importlib
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import analyzer
from tests.api_user_script import main as user_script

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs" / "howto" / "python-api.md"
USER_SCRIPT = ROOT / "tests" / "api_user_script.py"

PUBLIC = [
    "COMMANDS",
    "Decoder",
    "Event",
    "Finding",
    "Listener",
    "Recording",
    "analyze",
    "can_message",
    "encode",
    "read",
    "status_message",
    "tcp_frame",
    "text_messages",
]
# The modules whose docstrings hold the public names' examples.
DOCUMENTED = [
    "analyzer",
    "analyzer.api.analysis",
    "analyzer.api.commands",
    "analyzer.api.decoding",
    "analyzer.api.encoding",
    "analyzer.api.listener",
    "analyzer.api.messages",
    "analyzer.api.reading",
    "analyzer.api.recording",
    "analyzer.protocol.types",
]


def test_all_lists_exactly_the_public_names() -> None:
    assert analyzer.__all__ == PUBLIC
    assert analyzer._PUBLIC.keys() == set(PUBLIC)
    for name in PUBLIC:
        value = getattr(analyzer, name)
        assert value is getattr(importlib.import_module(analyzer._PUBLIC[name]), name)
        assert name in dir(analyzer)
    with pytest.raises(AttributeError, match="no attribute 'decode'"):
        analyzer.decode  # type: ignore[attr-defined]  # noqa: B018


def test_every_public_name_is_documented_with_an_example() -> None:
    """A docstring with examples for each (COMMANDS, a tuple, has its module's), and a
    place on the Python API page."""
    finder = doctest.DocTestFinder(exclude_empty=True)
    with_examples = {
        test.name
        for name in DOCUMENTED
        for test in finder.find(importlib.import_module(name))
        if test.examples
    }
    for name in PUBLIC:
        value = getattr(analyzer, name)
        where = "analyzer.api.commands" if name == "COMMANDS" else f"{value.__module__}.{name}"
        assert where in with_examples, f"{name}: no docstring example"
    text = DOCS.read_text(encoding="utf-8")
    assert [n for n in PUBLIC if f"`{n}`" not in text] == []


LOADED = """
import json, sys
import analyzer
{statement}
print(json.dumps(sorted(m for m in sys.modules if m.split(".")[0] in {modules!r})))
"""
HEAVY = ["analyzer", "can", "pyarrow", "av", "textual", "mcap", "duckdb", "foxglove", "dpkt"]


def loaded_after(statement: str) -> list[str]:
    code = LOADED.format(statement=statement, modules=set(HEAVY))
    done = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        check=True,
        encoding="utf-8",
    )
    return list(json.loads(done.stdout))


def test_importing_the_package_loads_nothing_else() -> None:
    assert loaded_after("") == ["analyzer", "analyzer.version"]  # the version: no import
    light = loaded_after("from analyzer import encode, tcp_frame, COMMANDS, Decoder, Event")
    assert not [m for m in light if m.split(".")[0] in HEAVY[1:]], light
    reading = loaded_after("from analyzer import read, analyze, Recording, can_message")
    assert not [m for m in reading if m.split(".")[0] in ("pyarrow", "av", "textual", "can")]


@pytest.fixture
def in_samples_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A working folder where ``samples/`` is the source tree's, as the examples assume."""
    try:
        (tmp_path / "samples").symlink_to(ROOT / "samples")
    except OSError:  # Windows without developer mode: a copy does as well
        shutil.copytree(ROOT / "samples", tmp_path / "samples")
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize("module", DOCUMENTED)
def test_the_docstring_examples_run(module: str, in_samples_folder: Path) -> None:
    result = doctest.testmod(importlib.import_module(module), optionflags=doctest.ELLIPSIS)
    assert result.failed == 0 and result.attempted > 0


@pytest.mark.slow
def test_the_examples_of_the_python_api_page_run(
    in_samples_folder: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """docs/howto/python-api.md: its shell step (the recording its examples read), then every pycon
    block in order, sharing one namespace, as a reader pasting them would."""
    from analyzer.cli import main

    text = DOCS.read_text(encoding="utf-8")
    commands = re.findall(r"^    (gimbal-analyzer .*)$", text, re.M)
    assert commands == [
        "gimbal-analyzer demo --no-tui --duration 10 --video main -o demo.mcap",
        "gimbal-analyzer convert samples/flight-candump.log -o flight.mcap",
    ]
    for line in commands:
        assert main(shlex.split(line)[1:]) == 0
    parser = doctest.DocTestParser()
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    globs: dict[str, object] = {}
    blocks = list(re.finditer(r"^```pycon\n(.*?)^```$", text, re.M | re.S))
    assert len(blocks) >= 10
    for block in blocks:
        line = text[: block.start(1)].count("\n")
        test = parser.get_doctest(block.group(1), globs, DOCS.name, str(DOCS), line)
        runner.run(test, clear_globs=False)
        globs.update(test.globs)
    failed, attempted = runner.summarize(verbose=False)
    assert failed == 0, capsys.readouterr().out
    assert attempted > 50


def test_the_readme_points_to_the_python_api_page() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "(docs/howto/python-api.md)" in readme


# -- mypy --strict, as a user of the installed package runs it --------------------------------


def mypy_strict(script: Path, tmp_path: Path) -> subprocess.CompletedProcess[str]:
    """``mypy --strict`` on ``script`` with this source tree's package (its py.typed): no
    project configuration, the package's own modules followed but not themselves judged,
    as for an installed package."""
    config = tmp_path / "mypy.ini"
    config.write_text("[mypy]\n", encoding="utf-8")
    return subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", "--config-file", str(config),
         "--follow-imports=silent", "--cache-dir", str(tmp_path / "cache"), str(script)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=tmp_path,
        env={**os.environ, "MYPYPATH": str(ROOT)}, encoding="utf-8",
    )  # fmt: skip


WRONG = """\
import analyzer
from analyzer import Decoder, analyze, encode, read

events = Decoder().feed_can("0x0F01", b"", 1.0)
data: int = encode("forward")
for finding in analyze(read("x.log")):
    finding.verdicts
analyzer.decode("x.log")
"""


@pytest.mark.slow
def test_a_users_script_passes_mypy_strict_and_its_mistakes_do_not(tmp_path: Path) -> None:
    assert (ROOT / "analyzer" / "py.typed").exists()
    done = mypy_strict(USER_SCRIPT, tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "Success: no issues found in 1 source file" in done.stdout
    # The same mypy sees this tree's real signatures: each mistake is named.
    wrong = tmp_path / "wrong.py"
    wrong.write_text(WRONG, encoding="utf-8")
    done = mypy_strict(wrong, tmp_path)
    errors = [
        line.split(": error: ")[1] for line in done.stdout.splitlines() if ": error: " in line
    ]
    assert errors == [
        'Argument 1 to "feed_can" of "Decoder" has incompatible type "str"; expected "int"  [arg-type]',
        'Incompatible types in assignment (expression has type "bytes", variable has type "int")  [assignment]',
        '"Finding" has no attribute "verdicts"; maybe "verdict"?  [attr-defined]',
        'Module has no attribute "decode"; maybe "encode" or "Decoder"?  [attr-defined]',
    ], done.stdout


def test_the_users_script_runs(in_samples_folder: Path) -> None:
    user_script("samples/flight-candump.log")
