"""The manual: it builds with warnings as errors, its reference has an entry for every
sub-command and option, protocol command, topic, exit code and public API name, and
its index opens in headless Chromium with the navigation and a search that finds pages.

The build is made once per run (``python -m sphinx -W --keep-going``), or taken from
``GIMBAL_DOCS_BUILD`` when CI built it already. Without Sphinx (``pip install
'.[docs]'``) or Chromium the tests skip, unless ``GIMBAL_REQUIRE_SPHINX=1`` /
``GIMBAL_REQUIRE_CHROMIUM=1`` (as in ``.ci/run``) make them fail.
"""

from __future__ import annotations

import argparse
import html
import importlib.util
import os
import re
import subprocess
import sys
import types
from pathlib import Path

import pytest

import analyzer
from analyzer.cli import build_parser
from tests.test_report_command import CHROMIUM, CHROMIUM_FLAGS

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
REQUIRE_SPHINX = os.environ.get("GIMBAL_REQUIRE_SPHINX") == "1"
REQUIRE_CHROMIUM = os.environ.get("GIMBAL_REQUIRE_CHROMIUM") == "1"
DOCS_PACKAGES = ("sphinx", "myst_parser", "furo")


def _sphinx_missing() -> str | None:
    missing = [name for name in DOCS_PACKAGES if importlib.util.find_spec(name) is None]
    return f"{', '.join(missing)} not installed (pip install '.[docs]')" if missing else None


def _need_sphinx() -> None:
    why = _sphinx_missing()
    if why:
        if REQUIRE_SPHINX:
            pytest.fail(why)
        pytest.skip(why)


@pytest.fixture(scope="session")
def built(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The built manual: CI's build when it names one, else a fresh build with -W."""
    given = os.environ.get("GIMBAL_DOCS_BUILD")
    if given and (Path(given) / "index.html").is_file():
        return Path(given)
    _need_sphinx()
    out = tmp_path_factory.mktemp("manual")
    done = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", DOCS, out],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
        cwd=ROOT,
        encoding="utf-8",
    )
    assert done.returncode == 0, f"the manual does not build:\n{done.stderr[-4000:]}"
    assert "WARNING" not in done.stderr, done.stderr[-4000:]
    return out


def page(built: Path, name: str) -> str:
    return (built / name).read_text(encoding="utf-8")


def _docs_extension(name: str) -> types.ModuleType:
    _need_sphinx()
    sys.path.insert(0, str(DOCS / "_ext"))
    try:
        return importlib.import_module(name)
    finally:
        sys.path.remove(str(DOCS / "_ext"))


# -- the command line ----------------------------------------------------------------------


def commands(
    parser: argparse.ArgumentParser, prog: str = "gimbal-analyzer"
) -> list[tuple[str, argparse.ArgumentParser]]:
    """(command line, parser) of the program and every sub-command, found here from the
    parsers themselves, not from the extension that writes the page."""
    found = [(prog, parser)]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                found += commands(sub, f"{prog} {name}")
    return found


def names_in_help(parser: argparse.ArgumentParser) -> set[str]:
    """What ``--help`` lists: every option string, and each positional's name."""
    formatter = parser._get_formatter()
    names: set[str] = set()
    for action in parser._actions:
        if action.help == argparse.SUPPRESS or isinstance(action, argparse._SubParsersAction):
            continue
        if action.option_strings:
            names.update(action.option_strings)
        else:
            names.add(formatter._format_action_invocation(action))
    return names


def _anchor(command: str) -> str:
    label = "cli-" + (command.split(" ", 1)[1] if " " in command else "main")
    return re.sub(r"[^a-z0-9]+", "-", label.lower())


def documented_options(built: Path) -> dict[str, set[str]]:
    """Command line -> the option names the built reference shows in its section."""
    text = page(built, "reference/cli.html")
    found = commands(build_parser())
    starts = []
    for command, _ in found:
        at = text.find(f'<span id="{_anchor(command)}"></span>')
        assert at >= 0, f"the reference has no section for `{command}`"
        starts.append(at)
    out = {}
    for index, (command, _) in enumerate(found):
        end = starts[index + 1] if index + 1 < len(starts) else len(text)
        section = text[starts[index] : end]
        shown = re.findall(
            r'<span class="sig-name descname"><span class="pre">(.*?)</span>', section
        )
        out[command] = {html.unescape(name) for name in shown}
    return out


@pytest.mark.slow
def test_every_sub_command_and_every_option_of_help_has_its_entry(built: Path) -> None:
    shown = documented_options(built)
    found = commands(build_parser())
    assert len(found) > 18  # the program, its commands, and send's command sub-commands
    for command, parser in found:
        missing = names_in_help(parser) - shown[command]
        assert not missing, f"{command}: no entry for {sorted(missing)}"


@pytest.mark.slow
def test_an_option_without_help_fails_the_build() -> None:
    cli_reference = _docs_extension("cli_reference")
    parser = argparse.ArgumentParser(prog="gimbal-analyzer x")
    parser.add_argument("--said", help="has its words")
    parser.add_argument("--silent")
    missing: list[str] = []
    rst = cli_reference.command_rst("gimbal-analyzer x", "one line", parser, missing)
    assert missing == ["gimbal-analyzer x --silent SILENT"]
    assert ".. option:: --said SAID" in rst and "   has its words" in rst


@pytest.mark.slow
def test_help_texts_are_shown_as_written(built: Path) -> None:
    text = html.unescape(re.sub(r"<[^>]+>", "", page(built, "reference/cli.html")))
    decode = build_parser("decode").commands["decode"]
    for action in decode._actions:
        if action.help and action.help != argparse.SUPPRESS:
            words = " ".join(decode._get_formatter()._expand_help(action).split())
            assert words in " ".join(text.split()), words


def test_the_reference_shows_option_groups_and_no_line_runs_off_the_page(built: Path) -> None:
    """The exit-code table and camera video's words, wrapped (a literal block of the
    page does not wrap: a line of 394 characters runs off it)."""
    source = page(built, "reference/cli.html")
    blocks = [
        html.unescape(re.sub(r"<[^>]+>", "", b))
        for b in re.findall(r"<pre>(.*?)</pre>", source, re.S)
    ]
    assert blocks
    assert [line for b in blocks for line in b.splitlines() if len(line) > 100] == []
    text = " ".join(html.unescape(re.sub(r"<[^>]+>", "", source)).split())
    assert "camera video: Record the camera's RTSP streams into the same file" in text
    assert "0 success; also a record / monitor / demo ended by Ctrl-C" in text


# -- the protocol, topics, exit codes --------------------------------------------------------


@pytest.mark.slow
def test_every_protocol_command_and_message_has_its_entry(built: Path) -> None:
    from analyzer.protocol.command_table import COMMANDS
    from analyzer.protocol.feedback import LAYOUTS
    from analyzer.protocol.uav import STATUS_FRAMES

    text = html.unescape(re.sub(r"<[^>]+>", "", page(built, "reference/protocol.html")))
    for row in COMMANDS:
        assert f"0x{row.cmd:02X} {row.name} {row.title}" in " ".join(text.split()), row.name
        for field in row.all_fields():
            assert field.name in text, (row.name, field.name)
    for layout in LAYOUTS.values():
        assert f"{layout.name} (length byte 0x{layout.length_byte:02X}" in text
    for status in STATUS_FRAMES.values():
        assert f"{status.name} (CAN ID 0x{status.can_id:08X}" in text


@pytest.mark.slow
def test_every_topic_has_its_fields_and_schema(built: Path) -> None:
    from analyzer.protocol.schema import topic_schemas

    text = html.unescape(re.sub(r"<[^>]+>", "", page(built, "reference/schemas.html")))
    for topic, schema in topic_schemas().items():
        assert topic in text
        for name in schema["properties"]:
            assert name in text, (topic, name)


@pytest.mark.slow
def test_every_exit_code_has_its_entry(built: Path) -> None:
    from analyzer.errors import EXIT_CODES

    text = " ".join(
        html.unescape(re.sub(r"<[^>]+>", "", page(built, "reference/exit-codes.html"))).split()
    )
    for code, words in EXIT_CODES:
        assert f"{code} {' '.join(words.split())}" in text


# -- the Python API --------------------------------------------------------------------------


@pytest.mark.slow
def test_every_public_name_has_its_entry(built: Path) -> None:
    text = page(built, "reference/python-api.html")
    for name in getattr(analyzer, "__all__", ()):
        assert f'id="analyzer.{name}"' in text, f"analyzer.{name} has no entry"
    # COMMANDS, a tuple, has its own docstring, not the one of Python's tuple
    entry = text[text.index('id="analyzer.COMMANDS"') :]
    entry = entry[: entry.index("</dl>")]
    assert "Every command of the protocol document" in entry
    assert "immutable sequence" not in entry


def test_the_api_page_documents_classes_functions_and_tables_by_their_kind(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    api_reference = _docs_extension("api_reference")
    (tmp_path / "package_defs.py").write_text(
        'COMMANDS: tuple[int, ...] = (1, 2)\n"""The table,\n  of two."""\nUNDOCUMENTED = 3\n',
        encoding="utf-8",
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    package = types.ModuleType("package")

    class Decoder:
        """Frames in, events out."""

    def decode(data: bytes) -> list[str]:
        """Decode."""
        return []

    package.Decoder = Decoder  # type: ignore[attr-defined]
    package.decode = decode  # type: ignore[attr-defined]
    package.COMMANDS = (1, 2)  # type: ignore[attr-defined]
    package.UNDOCUMENTED = 3  # type: ignore[attr-defined]
    package._PUBLIC = {"COMMANDS": "package_defs", "UNDOCUMENTED": "package_defs"}  # type: ignore[attr-defined]
    package.__all__ = ["Decoder", "decode", "COMMANDS", "UNDOCUMENTED", "gone"]  # type: ignore[attr-defined]
    lines, missing = api_reference.api_rst(package)
    assert ".. autoclass:: package.Decoder" in lines
    assert ".. autofunction:: package.decode" in lines
    at = lines.index(".. py:data:: package.COMMANDS")
    assert lines[at + 1 : at + 5] == ["", "   The table,", "   of two.", ""]
    assert missing == ["UNDOCUMENTED", "gone"]


# -- in a browser ----------------------------------------------------------------------------


def _dump_dom(target: str, tmp_path: Path) -> str:
    if CHROMIUM is None:
        if REQUIRE_CHROMIUM:
            pytest.fail("chromium is not installed (.ci/run installs it)")
        pytest.skip("chromium is not installed")
    command = [
        CHROMIUM,
        *CHROMIUM_FLAGS,
        f"--user-data-dir={tmp_path / 'profile'}",
        "--dump-dom",
        target,
    ]
    done = subprocess.run(
        command, capture_output=True, text=True, timeout=120, check=False, encoding="utf-8"
    )
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


@pytest.mark.slow
def test_the_index_opens_in_chromium_with_the_navigation_and_a_search_box(
    built: Path, tmp_path: Path
) -> None:
    dom = _dump_dom((built / "index.html").as_uri(), tmp_path)
    navigation = dom[dom.index('class="sidebar-tree"') :]
    for caption in ("Tutorials", "How-to guides: files", "Reference", "Explanation"):
        assert f'<span class="caption-text">{caption}</span>' in navigation, caption
    for target in ("tutorials/first-capture.html", "reference/cli.html", "architecture.html"):
        assert f'href="{target}"' in navigation, target
    assert re.search(r'<form class="sidebar-search-container"[^>]*action="search.html"', dom)
    assert re.search(r'<input class="sidebar-search"[^>]*name="q"', dom)


@pytest.mark.slow
def test_the_search_finds_the_pages_of_a_word(built: Path, tmp_path: Path) -> None:
    dom = _dump_dom((built / "search.html").as_uri() + "?q=DataFlash", tmp_path)
    results = re.search(r'<ul[^>]*class="search"[^>]*>(.*?)</ul>', dom, re.S)
    assert results, "the search page listed no results"
    assert 'href="howto/input-formats.html' in results.group(1)
