"""Every text file the project opens says its encoding: UTF-8 on Windows too.

Windows opens text files in its ANSI code page (cp1252 and the like) unless told: a
manual page or a log with a degree sign would read as something else, or not at all.
This reads the code (the analyzer, its tests, benchmarks and the manual's extensions)
and finds each call that opens a file in text mode without ``encoding=``.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CHECKED = ("analyzer", "tests", "benchmarks", "docs", ".ci", "fuzz")
_MODE = re.compile("[rwxabt+]+")


def _text_mode(mode: ast.expr | None) -> bool:
    """A mode argument that opens in text mode (no mode at all: "r")."""
    if mode is None:
        return True
    if isinstance(mode, ast.Constant) and isinstance(mode.value, str):
        return "b" not in mode.value
    return False  # a mode worked out at run time: not judged here


def _argument(call: ast.Call, position: int, name: str) -> ast.expr | None:
    if len(call.args) > position:
        return call.args[position]
    return next((k.value for k in call.keywords if k.arg == name), None)


def _has(call: ast.Call, position: int, name: str) -> bool:
    return _argument(call, position, name) is not None or any(
        k.arg is None
        for k in call.keywords  # **options: not judged here
    )


def unspecified(call: ast.Call) -> str | None:
    """What the call opens without an encoding, None when it says one (or is binary)."""
    func = call.func
    name = (
        func.id
        if isinstance(func, ast.Name)
        else func.attr
        if isinstance(func, ast.Attribute)
        else ""
    )
    if name == "open" and isinstance(func, ast.Name):  # open(path, mode, buffering, encoding)
        if _text_mode(_argument(call, 1, "mode")) and not _has(call, 3, "encoding"):
            return "open()"
    elif name == "open" and isinstance(func, ast.Attribute):  # Path.open(mode, buffering, encoding)
        mode = _argument(call, 0, "mode")
        if mode is not None and not (
            isinstance(mode, ast.Constant)
            and isinstance(mode.value, str)
            and _MODE.match(mode.value)
        ):
            return None  # not a Path: a device, a prompt, av.open...
        if not call.args and not call.keywords:
            return None  # link.open(), reader.open(): not files
        if _text_mode(mode) and not _has(call, 2, "encoding"):
            return ".open()"
    elif name == "read_text" and not _has(call, 0, "encoding"):
        return ".read_text()"
    elif name == "write_text" and not _has(call, 1, "encoding"):
        return ".write_text()"
    elif name == "TextIOWrapper" and not _has(call, 1, "encoding"):
        return "TextIOWrapper()"
    elif name in {"run", "Popen", "check_output"}:
        text = _argument(call, 99, "text") or _argument(call, 99, "universal_newlines")
        if isinstance(text, ast.Constant) and text.value is True and not _has(call, 99, "encoding"):
            return f"subprocess {name}(text=True)"
    return None


def findings() -> list[str]:
    found = []
    for top in CHECKED:
        for path in sorted((ROOT / top).rglob("*.py")):
            if any(part.startswith(("venv", ".venv")) for part in path.parts):
                continue  # CI's virtual environments (.ci/venv, .ci/venv-3.10, ...)
            tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
            for node in ast.walk(tree):
                if isinstance(node, ast.Call) and (what := unspecified(node)):
                    found.append(f"{path.relative_to(ROOT)}:{node.lineno}: {what}")
    return found


def test_every_text_file_is_opened_with_its_encoding() -> None:
    found = findings()
    assert not found, 'text opened without encoding= (add encoding="utf-8"):\n' + "\n".join(found)


def test_the_check_finds_each_kind_of_call() -> None:
    calls = [
        "open(p)", "open(p, 'w')", "path.open('w')", "path.read_text()",
        "path.write_text(t)", "io.TextIOWrapper(b)", "subprocess.run(c, text=True)",
    ]  # fmt: skip
    fine = [
        "open(p, 'rb')", "open(p, encoding='utf-8')", "path.open('rb')", "link.open()",
        "path.read_text('utf-8')", "path.write_text(t, encoding='utf-8')", "av.open(url, x)",
        "io.TextIOWrapper(b, 'utf-8')", "subprocess.run(c, text=True, encoding='utf-8')",
        "subprocess.run(c)", "path.read_bytes()", "prompt.open('filter', text)",
    ]  # fmt: skip
    parse = lambda text: ast.parse(text).body[0].value  # noqa: E731
    assert all(unspecified(parse(c)) for c in calls)
    assert not any(unspecified(parse(c)) for c in fine)
