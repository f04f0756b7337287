"""The suite collects on Windows and macOS: what only POSIX or Linux has is behind a marker.

Read from the code (the other systems are not here to run it): no test module imports a
POSIX-only module when it is imported, no decorator calls a POSIX-only function, and a
test that sends POSIX signals, opens pseudo-terminals or makes symbolic links carries a
skip marker (``tests/platforms.py``) or sits in a module that does.
"""

from __future__ import annotations

import ast
from pathlib import Path

TESTS = Path(__file__).resolve().parent
POSIX_MODULES = {"pty", "fcntl", "termios", "tty", "resource", "grp", "pwd", "posix"}
# Calls that end pytest itself on Windows, are refused there, or need a privilege.
NEEDS_A_MARKER = {
    "os.kill": "os.kill (Windows: ends the process at once)",
    "os.killpg": "os.killpg",
    "send_signal": "send_signal (Windows: SIGINT refused, SIGTERM ends it at once)",
    "os.openpty": "pseudo-terminals",
    "symlink_to": "symbolic links (Windows: developer mode only)",
    "socketpair": "socketpair(AF_UNIX)",
}


def modules() -> list[Path]:
    return sorted(p for p in TESTS.glob("*.py") if p.name != "test_platform_markers.py")


def _guarded_by_import_error(node: ast.Try) -> bool:
    return any(
        isinstance(h.type, ast.Name) and h.type.id in {"ImportError", "ModuleNotFoundError"}
        for h in node.handlers
    )


def imported_at_import_time(tree: ast.Module) -> set[str]:
    """POSIX-only modules imported by the module's own code (not inside a function or
    a ``try`` that takes an ImportError)."""
    found: set[str] = set()
    pending: list[ast.stmt] = list(tree.body)
    while pending:
        node = pending.pop()
        if isinstance(node, ast.Import):
            found |= {a.name.split(".")[0] for a in node.names} & POSIX_MODULES
        elif isinstance(node, ast.ImportFrom) and node.module:
            found |= {node.module.split(".")[0]} & POSIX_MODULES
        elif isinstance(node, ast.If):
            pending += node.body + node.orelse
        elif isinstance(node, ast.Try) and not _guarded_by_import_error(node):
            pending += node.body
    return found


def _called(node: ast.AST) -> set[str]:
    names = set()
    for call in ast.walk(node):
        if isinstance(call, ast.Call) and isinstance(call.func, ast.Attribute):
            owner = call.func.value
            os_call = isinstance(owner, ast.Name) and owner.id == "os"
            names.add(f"os.{call.func.attr}" if os_call else call.func.attr)
    return names


def _marked(decorators: list[ast.expr]) -> bool:
    """A skip marker: one of tests.platforms' or a pytest.mark.skipif."""
    for decorator in decorators:
        text = ast.unparse(decorator)
        if text.startswith(("posix_", "pseudo_terminals", "symlinks", "linux", "pytest.mark.skip")):
            return True
    return False


def unmarked_tests(tree: ast.Module) -> list[str]:
    if any(
        isinstance(node, ast.Assign)
        and any(getattr(t, "id", "") == "pytestmark" for t in node.targets)
        for node in tree.body
    ):
        return []  # the module's own marker
    found = []
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.name.startswith("test_"):
            needs = _called(node) & NEEDS_A_MARKER.keys()
            if needs and not _marked(node.decorator_list):
                found.append(f"{node.name}: {', '.join(NEEDS_A_MARKER[n] for n in sorted(needs))}")
    return found


def test_no_test_module_imports_a_posix_module_when_imported() -> None:
    found = {}
    for path in modules():
        names = imported_at_import_time(ast.parse(path.read_text(encoding="utf-8")))
        if names:
            found[path.name] = sorted(names)
    assert not found, f"import these inside the tests that need them: {found}"


def test_no_decorator_calls_a_posix_only_function() -> None:
    found = []
    for path in modules():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef):
                for decorator in node.decorator_list:
                    text = ast.unparse(decorator)
                    for name in ("geteuid", "getuid", "getgid", "SIGKILL", "SIGUSR1"):
                        if f"os.{name}()" in text and "hasattr" not in text:
                            found.append(f"{path.name}: {node.name}")
    assert not found, f"decorators that fail on Windows when collected: {found}"


def test_tests_that_need_posix_carry_a_marker() -> None:
    found = []
    for path in modules():
        found += [
            f"{path.name}: {t}" for t in unmarked_tests(ast.parse(path.read_text(encoding="utf-8")))
        ]
    assert not found, "add a marker of tests/platforms.py:\n" + "\n".join(found)


def test_the_checks_find_what_they_look_for() -> None:
    source = (
        "import os\nimport pty\ntry:\n    import resource\nexcept ImportError:\n    pass\n"
        "def test_a():\n    os.kill(1, 15)\n    proc.kill()\n"
        "@posix_signals\ndef test_b():\n    os.kill(1, 15)\n"
    )
    tree = ast.parse(source)
    assert imported_at_import_time(tree) == {"pty"}
    assert unmarked_tests(tree) == ["test_a: os.kill (Windows: ends the process at once)"]
