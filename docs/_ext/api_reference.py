"""Sphinx directive ``gimbal-api``: an autodoc entry for every name in ``analyzer.__all__``.

The list is read when the manual is built, so a name added to ``__all__`` gets its entry
(from its docstring) without touching the manual; a name that is not importable, or a
docstring autodoc cannot read, is a warning, which ``-W`` makes a failed build. A table
or a constant (``COMMANDS``) has the docstring written under its assignment, not the one
of its value's type (a tuple's).
"""

from __future__ import annotations

import ast
import importlib
import inspect
import itertools
from types import ModuleType

from code_dependencies import note_code_dependencies
from docutils import nodes
from docutils.statemachine import StringList
from sphinx.application import Sphinx
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective
from sphinx.util.nodes import nested_parse_with_titles

logger = logging.getLogger(__name__)


def public_names(module: ModuleType) -> list[str]:
    """The names the package exports, in the order ``__all__`` gives them."""
    return list(getattr(module, "__all__", ()))


def api_rst(module: ModuleType) -> tuple[list[str], list[str]]:
    """(reStructuredText of an autodoc entry per public name, names that are missing)."""
    lines: list[str] = []
    missing: list[str] = []
    for name in public_names(module):
        if not hasattr(module, name):
            missing.append(name)
            continue
        value = getattr(module, name)
        target = f"{module.__name__}.{name}"
        if inspect.isclass(value):
            lines += [f".. autoclass:: {target}", "   :members:", ""]
        elif inspect.isfunction(value) or inspect.isbuiltin(value):
            lines += [f".. autofunction:: {target}", ""]
        elif inspect.ismodule(value):
            lines += [f".. automodule:: {value.__name__}", "   :members:", ""]
        else:  # a table or a constant: its own docstring, not its (long) value's type's
            doc = attribute_doc(_defining_module(module, name), name)
            if doc is None:
                missing.append(name)
                continue
            lines += [f".. py:data:: {target}", ""]
            lines += [f"   {line}".rstrip() for line in doc.splitlines()] + [""]
    return lines, missing


def _defining_module(module: ModuleType, name: str) -> ModuleType:
    """The module that defines a public name (a package's lazy table says which)."""
    lazy: dict[str, str] = getattr(module, "_PUBLIC", {})
    return importlib.import_module(lazy[name]) if name in lazy else module


def attribute_doc(module: ModuleType, name: str) -> str | None:
    """The docstring written under ``name = ...`` (or ``name: T = ...``) at the top level
    of ``module``'s source; None when there is none."""
    try:
        source = inspect.getsource(module)
    except (OSError, TypeError):
        return None
    body = ast.parse(source).body
    for node, after in itertools.pairwise(body):
        targets = node.targets if isinstance(node, ast.Assign) else [getattr(node, "target", None)]
        named = any(isinstance(t, ast.Name) and t.id == name for t in targets)
        if named and isinstance(after, ast.Expr) and isinstance(after.value, ast.Constant):
            text = after.value.value
            return inspect.cleandoc(text) if isinstance(text, str) else None
    return None


class PublicApi(SphinxDirective):
    """``.. gimbal-api:: analyzer``: every public name of the package, from its docstring."""

    required_arguments = 1
    has_content = False

    def run(self) -> list[nodes.Node]:
        note_code_dependencies(self.env)
        module = importlib.import_module(self.arguments[0])
        lines, missing = api_rst(module)
        for name in missing:
            logger.warning(
                "%s.__all__ names %s, which the package does not have (or a table or "
                "constant without a docstring under it)",
                module.__name__,
                name,
                location=self.get_location(),
            )
        if not lines:
            name = nodes.literal(text=f"{module.__name__}.__all__")
            return [nodes.paragraph("", "", name, nodes.Text(" names nothing yet."))]
        container = nodes.section()
        container.document = self.state.document
        nested_parse_with_titles(self.state, StringList(lines, "<gimbal-api>"), container)
        return list(container.children)


def setup(app: Sphinx) -> dict[str, object]:
    app.add_directive("gimbal-api", PublicApi)
    return {"version": "1", "parallel_read_safe": True}
