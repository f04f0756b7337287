"""The quick tier: ``python -m pytest -m "not slow"`` leaves out what takes seconds.

A test is marked ``slow`` (``@pytest.mark.slow`` or a module's ``pytestmark``) when it
takes a second or more on a 2-core machine, and always when it drives a real RTSP
camera, Chromium, a Dask cluster or a demo that runs for a second or more (the ArduPilot
demo among them). The check below reads each collected test, the fixtures it uses and
the helpers of its module it calls, and fails for one that does any of that unmarked;
in a quick run (``-m "not slow"``) it fails for one that came through. The quick tier
keeps at least 60 % of the tests.
"""

from __future__ import annotations

import ast
import functools
import inspect
import re
import subprocess
import sys
import textwrap
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from analyzer.commands.demo import PLAIN_DURATION

TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent
RTSP_FIXTURES = frozenset({"rtsp_camera", "rtsp_camera_factory", "rtsp_available"})
LONG_DEMO_S = 1.0
QUICK_SHARE = 0.6
RTSP, BROWSER, DASK = "a real RTSP camera", "Chromium", "a Dask cluster"
LONG_DEMO, ARDUPILOT_DEMO = "a demo of a second or more", "the ArduPilot demo"


@functools.cache
def reach(function: Callable[..., Any]) -> tuple[ast.AST, ...]:
    """The syntax of ``function`` and of every function of the tests it calls, and so on."""
    seen: set[Callable[..., Any]] = set()
    trees: list[ast.AST] = []
    pending = [function]
    while pending:
        current = pending.pop()
        if current in seen:
            continue
        seen.add(current)
        try:
            tree = ast.parse(textwrap.dedent(inspect.getsource(current)))
        except (OSError, TypeError, SyntaxError):
            continue
        trees.append(tree)
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
                called = current.__globals__.get(node.func.id)
                if inspect.isfunction(called) and ours(inspect.unwrap(called)):
                    pending.append(inspect.unwrap(called))
    return tuple(trees)


def ours(function: Callable[..., Any]) -> bool:
    """A function of the tests (not of pytest or of a library)."""
    try:
        return Path(inspect.getsourcefile(function) or "").is_relative_to(TESTS)
    except TypeError:
        return False


def identifiers(trees: tuple[ast.AST, ...]) -> set[str]:
    """The names the code uses (not its words: a docstring may speak of Chromium)."""
    names: set[str] = set()
    for tree in trees:
        for node in ast.walk(tree):
            if isinstance(node, ast.Name):
                names.add(node.id)
            elif isinstance(node, ast.Attribute):
                names.add(node.attr)
            elif isinstance(node, ast.FunctionDef):
                names.add(node.name)
    return names


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


def demo_seconds(trees: tuple[ast.AST, ...]) -> float:
    """How long the longest demo the code runs lasts: its ``--duration``, or the default
    when it has none (a demo the code expects to be refused, exit 2, runs for none)."""
    longest = 0.0
    for tree in trees:
        refused = any(
            isinstance(n, ast.Compare)
            and any(isinstance(c, ast.Constant) and c.value == 2 for c in n.comparators)
            for n in ast.walk(tree)
        )
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
    trees = reach(function) + tuple(t for f in fixture_functions(item) for t in reach(f))
    names = identifiers(trees)
    if any("chromium" in name.lower() for name in names):
        return BROWSER
    if "LocalCluster" in names or {"distributed", "Client"} <= names:
        return DASK
    if demo_seconds(trees) >= LONG_DEMO_S:
        return ARDUPILOT_DEMO if "--ardupilot" in constants(trees) else LONG_DEMO
    return None


def constants(trees: tuple[ast.AST, ...]) -> set[str]:
    return {
        node.value
        for tree in trees
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant) and isinstance(node.value, str)
    }


def test_what_takes_seconds_by_its_nature_is_marked_slow(request: pytest.FixtureRequest) -> None:
    """Every such test carries the mark (so a quick run has none of them); a full run
    finds each kind, which shows the check sees them."""
    kinds: dict[str, list[str]] = {}
    for item in request.session.items:
        why = why_slow(item)
        if why:
            marked = item.get_closest_marker("slow") is not None
            kinds.setdefault(why, []).append("" if marked else item.nodeid)
    unmarked = [f"{node}: {why}" for why, nodes in kinds.items() for node in nodes if node]
    assert not unmarked, "mark these @pytest.mark.slow:\n" + "\n".join(unmarked)
    everything = not request.config.getoption("markexpr") and not request.config.getoption(
        "keyword"
    )
    if everything and len(request.session.items) > 1000:  # the whole suite was collected
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
    assert demo_seconds(reach(_a_long_demo)) == 4.5
    assert demo_seconds(reach(_a_plain_demo)) == PLAIN_DURATION
    assert demo_seconds(reach(_a_refused_demo)) == 0.0
    assert demo_seconds(reach(_a_short_demo)) == 0.3


@pytest.mark.slow
def test_the_quick_tier_keeps_most_of_the_tests() -> None:
    """``-m "not slow"`` selects at least 60 % of the tests and deselects the rest."""
    command = [sys.executable, "-m", "pytest", "--collect-only", "-q", "-m", "not slow"]
    options = ["-o", "addopts=--strict-markers", "-p", "no:cacheprovider"]  # one -q: the count
    done = subprocess.run([*command, *options], cwd=ROOT, capture_output=True, text=True)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    counts = re.search(r"(\d+)/(\d+) tests collected \((\d+) deselected\)", done.stdout)
    assert counts, done.stdout[-2000:]
    quick, total, slow = map(int, counts.groups())
    assert slow > 0 and quick + slow == total
    assert quick >= QUICK_SHARE * total, f"only {quick} of {total} tests in the quick tier"
