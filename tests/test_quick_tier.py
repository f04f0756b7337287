"""The quick tier: ``python -m pytest -m "not slow"`` leaves out what takes seconds.

A test is marked ``slow`` (``@pytest.mark.slow`` or a module's ``pytestmark``) when it
takes a second or more on a 2-core machine, and always when it drives a real RTSP
camera, Chromium, a Dask cluster or a demo that runs for a second or more (the ArduPilot
demo among them). The check below reads every collected test (in a quick run too, before
``-m "not slow"`` leaves some out), the fixtures it uses and the helpers it calls, and
fails for one that does any of that unmarked. The quick tier keeps at least 60 % of
the tests.
"""

from __future__ import annotations

import ast
import functools
import inspect
import os
import re
import subprocess
import sys
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from analyzer.commands.demo import PLAIN_DURATION
from tests.collected import ALL_ITEMS

TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent
RTSP_FIXTURES = frozenset({"rtsp_camera", "rtsp_camera_factory", "rtsp_available"})
LONG_DEMO_S = 1.0
QUICK_SHARE = 0.6
RTSP, BROWSER, DASK = "a real RTSP camera", "Chromium", "a Dask cluster"
LONG_DEMO, ARDUPILOT_DEMO = "a demo of a second or more", "the ArduPilot demo"


@dataclass(frozen=True)
class Facts:
    """What one function's code shows: the names it uses (not its words: a docstring
    may speak of Chromium), its string constants, the longest demo it runs, and the
    functions of the tests it calls."""

    names: frozenset[str] = frozenset()
    strings: frozenset[str] = frozenset()
    demo_s: float = 0.0
    calls: tuple[Callable[..., Any], ...] = ()


@functools.cache
def definitions(path: str) -> dict[int, ast.AST]:
    """The functions a file defines, by the line of their ``def`` and of their first
    decorator (a file read once: far quicker than inspect.getsource for each)."""
    try:
        tree = ast.parse(Path(path).read_text(encoding="utf-8"))
    except (OSError, SyntaxError):
        return {}
    found: dict[int, ast.AST] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            for line in (node.lineno, *(d.lineno for d in node.decorator_list)):
                found.setdefault(line, node)
    return found


@functools.cache
def facts(function: Callable[..., Any]) -> Facts:
    code = getattr(function, "__code__", None)
    tree = definitions(code.co_filename).get(code.co_firstlineno) if code else None
    if tree is None:
        return Facts()
    names: set[str] = set()
    strings: set[str] = set()
    calls: list[Callable[..., Any]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Name):
            names.add(node.id)
        elif isinstance(node, ast.Attribute):
            names.add(node.attr)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            strings.add(node.value)
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            called = function.__globals__.get(node.func.id)
            if inspect.isfunction(called) and ours(inspect.unwrap(called)):
                calls.append(inspect.unwrap(called))
    return Facts(frozenset(names), frozenset(strings), demo_seconds(tree), tuple(calls))


@functools.cache
def reach(function: Callable[..., Any]) -> frozenset[Callable[..., Any]]:
    """``function`` and every function of the tests it calls, and so on."""
    seen: set[Callable[..., Any]] = set()
    pending = [function]
    while pending:
        current = pending.pop()
        if current not in seen:
            seen.add(current)
            pending += facts(current).calls
    return frozenset(seen)


@functools.cache
def ours(function: Callable[..., Any]) -> bool:
    """A function of the tests (not of pytest or of a library)."""
    try:
        return Path(inspect.getsourcefile(function) or "").is_relative_to(TESTS)
    except TypeError:
        return False


def fixture_functions(item: pytest.Item) -> Iterator[Callable[..., Any]]:
    """The functions of the project's fixtures a test uses."""
    info = getattr(item, "_fixtureinfo", None)
    for name in getattr(item, "fixturenames", ()):
        definitions = info.name2fixturedefs.get(name, ()) if info is not None else ()
        function = definitions[-1].func if definitions else None
        if function is not None and ours(function):
            yield function


def spelled_out(node: ast.AST) -> list[str]:
    """The strings of a list, a tuple or a call's arguments that start with a string."""
    parts = (
        node.elts if isinstance(node, ast.List | ast.Tuple)
        else node.args if isinstance(node, ast.Call) and len(node.args) > 1  # not f("demo")
        else []
    )  # fmt: skip
    if not parts or not (isinstance(parts[0], ast.Constant) and isinstance(parts[0].value, str)):
        return []
    return [p.value for p in parts if isinstance(p, ast.Constant) and isinstance(p.value, str)]


def demo_seconds(tree: ast.AST) -> float:
    """How long the longest demo the code runs lasts: its ``--duration``, or the default
    when it has none (a demo the code expects to be refused, exit 2, runs for none)."""
    refused = any(
        isinstance(n, ast.Compare)
        and any(isinstance(c, ast.Constant) and c.value == 2 for c in n.comparators)
        for n in ast.walk(tree)
    )
    longest = 0.0
    for node in ast.walk(tree):
        words = spelled_out(node)
        if not words or words[0] != "demo" or "--help" in words:
            continue
        if "--duration" in words[:-1]:
            longest = max(longest, float(words[words.index("--duration") + 1]))
        elif not refused:
            longest = max(longest, PLAIN_DURATION)
    return longest


def why_slow(item: pytest.Item) -> str | None:
    """What makes a test belong to the slow tier (None: nothing here says it does)."""
    if RTSP_FIXTURES & set(getattr(item, "fixturenames", ())):
        return RTSP
    function = getattr(item, "function", None)
    if function is None:
        return None
    functions = reach(function).union(*(reach(f) for f in fixture_functions(item)))
    found = [facts(f) for f in functions]
    names = frozenset().union(*(f.names for f in found))
    if any("chromium" in name.lower() for name in names):
        return BROWSER
    if "LocalCluster" in names or {"distributed", "Client"} <= names:
        return DASK
    if max((f.demo_s for f in found), default=0.0) >= LONG_DEMO_S:
        ardupilot = any("--ardupilot" in f.strings for f in found)
        return ARDUPILOT_DEMO if ardupilot else LONG_DEMO
    return None


def test_what_takes_seconds_by_its_nature_is_marked_slow(request: pytest.FixtureRequest) -> None:
    """Every such test carries the mark, so that a quick run has none of them; and when
    the whole suite was collected the check finds each kind (it sees them)."""
    items = request.config.stash.get(ALL_ITEMS, request.session.items)
    kinds: dict[str, list[str]] = {}
    for item in items:
        why = why_slow(item)
        if why:
            marked = item.get_closest_marker("slow") is not None
            kinds.setdefault(why, []).append("" if marked else item.nodeid)
    unmarked = [f"{node}: {why}" for why, nodes in kinds.items() for node in nodes if node]
    assert not unmarked, "mark these @pytest.mark.slow:\n" + "\n".join(unmarked)
    if len(items) > 1000:  # the whole suite was collected
        assert set(kinds) == {RTSP, BROWSER, DASK, LONG_DEMO, ARDUPILOT_DEMO}, kinds.keys()


def _a_long_demo() -> None:  # read by the check below, never run
    args = ["demo", "--no-tui", "--stick", "--duration", "4.5", "-o", str(ROOT)]
    assert args


def _a_plain_demo(main: Callable[[list[str]], int]) -> None:
    assert main(["demo", "--no-tui"]) == 0


def _a_refused_demo(main: Callable[[list[str]], int]) -> None:
    assert main(["demo", "--no-tui", "-o", "/nonexistent/x.mcap"]) == 2


def _a_short_demo(main: Callable[[list[str]], int]) -> None:
    assert main(["demo", "--no-tui", "--duration", "0.3", "--clean"]) == 0


def test_the_check_reads_how_long_a_demo_runs() -> None:
    assert facts(_a_long_demo).demo_s == 4.5
    assert facts(_a_plain_demo).demo_s == PLAIN_DURATION
    assert facts(_a_refused_demo).demo_s == 0.0
    assert facts(_a_short_demo).demo_s == 0.3


@pytest.mark.slow
def test_the_quick_tier_keeps_most_of_the_tests() -> None:
    """``-m "not slow"`` selects at least 60 % of the tests and deselects the rest."""
    command = [sys.executable, "-m", "pytest", "--collect-only", "-q", "-m", "not slow"]
    options = ["-o", "addopts=--strict-markers", "-p", "no:cacheprovider"]  # one -q: the count
    env = {k: v for k, v in os.environ.items() if k != "PYTEST_ADDOPTS"}  # CI's -n 2
    done = subprocess.run(
        [*command, *options], cwd=ROOT, env=env, capture_output=True, text=True, encoding="utf-8"
    )
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    counts = re.search(r"(\d+)/(\d+) tests collected \((\d+) deselected\)", done.stdout)
    assert counts, done.stdout[-2000:]
    quick, total, slow = map(int, counts.groups())
    assert slow > 0 and quick + slow == total
    assert quick >= QUICK_SHARE * total, f"only {quick} of {total} tests in the quick tier"
