"""The generated pages depend on the code: a change to ``analyzer/`` rebuilds them."""

from __future__ import annotations

from pathlib import Path

from sphinx.environment import BuildEnvironment

PACKAGE = Path(__file__).resolve().parents[2] / "analyzer"


def note_code_dependencies(env: BuildEnvironment) -> None:
    """Make the page that is being read depend on every module of the package (and on
    the extensions), so an incremental build renders it again when they change."""
    for path in [*PACKAGE.rglob("*.py"), *Path(__file__).parent.glob("*.py")]:
        env.note_dependency(str(path))
