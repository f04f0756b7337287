"""The layers keep: imports point only down the layers, and no modules import each other."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "analyzer"
PROTOCOL = PACKAGE / "protocol"

# Bottom first. A module may import from its own package and from any package listed
# before its own; never from one listed after it. Every module of the analyzer must fall
# under one of these (a new package is placed here on purpose, not by accident).
LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("the tool's version and protocol document", ("version",)),
    ("the sans-IO protocol core", ("protocol",)),
    (
        "shared plumbing",
        (
            "errors",
            "extras",
            "portable",
            "wall_clock",
            "timefmt",
            "terminal_text",
            "ansi",
            "stdio",
            "output_file",
            "bus_figures",
            "bus_hints",
            "feedback_track",
            "tally",
            "progress",
            "capture_clock",
            "library_log",
            "pipeline_contracts",
            "pipeline",
        ),
    ),
    (
        "sources, inputs and sinks",
        (
            "scene",  # where the gimbal points, from the events: drawn by mcapio and report
            "sources",
            "video",
            "mcapio",
            "inputs",
            "input_options",
            "link_status",
            "render",
            "summary",
            "export",
        ),
    ),
    ("analysis", ("analysis",)),
    ("engines", ("capture", "live", "sim", "samplegen", "ardupilot")),
    ("user interfaces", ("report", "tui", "fleet", "check", "replay", "compare")),
    ("the Python API", ("api",)),  # what `import analyzer` gives integrators
    ("commands", ("commands", "cli", "__main__")),
)
# The package root re-exports the version (from analyzer.version) and the Python API:
# each public name of the API is imported when first used (PEP 562) or by a type
# checker, never by `import analyzer`, which runs before any module of the package.
# Those imports are no edge of the graph;
# test_the_package_root_imports_nothing_of_the_analyzer_when_imported holds it to that,
# and test_no_module_takes_a_name_from_the_package_root keeps the modules from it.
PACKAGE_ROOT = "analyzer"
ORDER = [package for _, packages in LAYERS for package in packages]


def module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imported_modules(path: Path) -> set[str]:
    """Every module ``path`` imports, at the top, inside a function or for type checking;
    ``from analyzer.x import y`` counts as importing ``analyzer.x.y`` when that is a
    module."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names


def analyzer_graph() -> dict[str, set[str]]:
    """Module -> the analyzer modules it imports (packages count as their __init__)."""
    paths = {module_name(path): path for path in PACKAGE.rglob("*.py")}
    return {
        name: {other for other in imported_modules(path) if other in paths and other != name}
        if name != PACKAGE_ROOT
        else set()
        for name, path in paths.items()
    }


def package_of(module: str) -> str:
    """``analyzer.inputs.pcap.reader`` -> ``inputs``; the package root itself -> ``version``
    (at import time it holds only the version, the lowest thing there is)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "version"


def test_every_module_has_a_place_in_the_layers() -> None:
    unplaced = sorted({package_of(m) for m in analyzer_graph()} - set(ORDER))
    assert not unplaced, f"put these in LAYERS (tests/test_layering.py): {unplaced}"


def test_imports_point_only_down_the_layers() -> None:
    rank = {package: i for i, package in enumerate(ORDER)}
    upward = sorted(
        f"{module} imports {other}"
        for module, imports in analyzer_graph().items()
        for other in imports
        if rank.get(package_of(other), -1) > rank.get(package_of(module), len(ORDER))
    )
    assert not upward, "imports that run up a layer:\n" + "\n".join(upward)


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected groups of more than one module (Tarjan's algorithm)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for other in sorted(graph.get(node, ())):
            if other not in index:
                visit(other)
                low[node] = min(low[node], low[other])
            elif other in on_stack:
                low[node] = min(low[node], index[other])
        if low[node] == index[node]:
            group = []
            while True:
                other = stack.pop()
                on_stack.discard(other)
                group.append(other)
                if other == node:
                    break
            if len(group) > 1:
                found.append(sorted(group))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def test_no_modules_import_each_other() -> None:
    found = circles(analyzer_graph())
    assert not found, "modules that import each other (directly or round a circle):\n" + (
        "\n".join(" <-> ".join(group) for group in found)
    )


def test_the_protocol_core_imports_only_itself_from_the_analyzer() -> None:
    upward = {
        f"{path.name}: {name}"
        for path in sorted(PROTOCOL.glob("*.py"))
        for name in imported_modules(path)
        if name.startswith("analyzer") and not name.startswith("analyzer.protocol")
    }
    assert not upward, f"analyzer.protocol imports from layers above it: {sorted(upward)}"


def test_the_package_root_imports_nothing_of_the_analyzer_when_imported() -> None:
    """Its re-exports sit in a function or under TYPE_CHECKING: nothing at import time."""
    tree = ast.parse((PACKAGE / "__init__.py").read_text(encoding="utf-8"))
    at_import: list[str] = []
    for node in tree.body:
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING":
            nodes: list[ast.stmt] = list(node.orelse)  # what runs when not type checking
        else:
            nodes = [node]
        for statement in nodes:
            if isinstance(statement, ast.Import | ast.ImportFrom):
                names = imported_modules_of(statement) - {VERSION}
                at_import += sorted(n for n in names if n.startswith(PACKAGE_ROOT))
    assert not at_import, f"analyzer/__init__.py imports at import time: {at_import}"


VERSION = "analyzer.version"  # the one module the root imports: it imports nothing


def test_no_module_takes_a_name_from_the_package_root() -> None:
    """The root re-exports the API, which imports nearly everything: a module that took
    ``__version__`` from it would sit in a circle with the API (for a type checker);
    it takes it from analyzer.version. Sub-modules (``from analyzer import timefmt``)
    are no names of the root."""
    modules = {module_name(path).rsplit(".", 1)[-1] for path in PACKAGE.glob("*.py")}
    modules |= {path.name for path in PACKAGE.iterdir() if (path / "__init__.py").is_file()}
    taken = sorted(
        f"{path.relative_to(ROOT)}: {alias.name}"
        for path in PACKAGE.rglob("*.py")
        if path != PACKAGE / "__init__.py"
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
        if isinstance(node, ast.ImportFrom) and node.module == PACKAGE_ROOT and not node.level
        for alias in node.names
        if alias.name not in modules
    )
    assert not taken, "names taken from the package root (take them where they live):\n" + (
        "\n".join(taken)
    )


def test_the_version_module_imports_nothing_of_the_analyzer() -> None:
    assert not {n for n in imported_modules(PACKAGE / "version.py") if n.startswith("analyzer")}


def imported_modules_of(node: ast.Import | ast.ImportFrom) -> set[str]:
    if isinstance(node, ast.Import):
        return {alias.name for alias in node.names}
    return {node.module or ""}


def test_the_checks_see_imports_inside_functions_and_for_type_checking(tmp_path: Path) -> None:
    module = tmp_path / "m.py"
    module.write_text(
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n    from analyzer.tally import Tally\n"
        "def f():\n    from analyzer.analysis.findings import VERDICTS\n",
        encoding="utf-8",
    )
    assert {"analyzer.tally", "analyzer.analysis.findings"} <= imported_modules(module)


def test_the_checks_find_an_upward_import_and_a_circle() -> None:
    assert circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    rank = {package: i for i, package in enumerate(ORDER)}
    assert rank["commands"] > rank["fleet"] > rank["analysis"] > rank["inputs"]
    assert rank["inputs"] > rank["protocol"]


def test_every_package_says_what_it_holds() -> None:
    silent = [
        str(init.relative_to(ROOT))
        for init in PACKAGE.rglob("__init__.py")
        if not (ast.get_docstring(ast.parse(init.read_text(encoding="utf-8"))) or "").strip()
    ]
    assert not silent, f"packages without a one-line docstring: {silent}"
