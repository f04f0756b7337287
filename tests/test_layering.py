"""The sans-IO protocol core imports nothing from the layers above it."""

from __future__ import annotations

import ast
from pathlib import Path

PROTOCOL = Path(__file__).resolve().parent.parent / "analyzer" / "protocol"


def imported_modules(path: Path) -> set[str]:
    """Every module ``path`` imports, at the top or inside a function."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
    return names


def test_the_protocol_core_imports_only_itself_from_the_analyzer() -> None:
    upward = {
        f"{path.name}: {name}"
        for path in sorted(PROTOCOL.glob("*.py"))
        for name in imported_modules(path)
        if name.startswith("analyzer") and not name.startswith("analyzer.protocol")
    }
    assert not upward, f"analyzer.protocol imports from layers above it: {sorted(upward)}"


def test_the_check_sees_imports_inside_functions(tmp_path: Path) -> None:
    module = tmp_path / "m.py"
    module.write_text("def f():\n    from analyzer.analysis.findings import VERDICTS\n")
    assert imported_modules(module) == {"analyzer.analysis.findings"}
