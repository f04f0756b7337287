"""Sphinx directive ``gimbal-api``: an autodoc entry for every name in ``analyzer.__all__``.

The list is read when the manual is built, so a name added to ``__all__`` gets its entry
(from its docstring) without touching the manual; a name that is not importable, or a
docstring autodoc cannot read, is a warning, which ``-W`` makes a failed build.
"""

from __future__ import annotations

import importlib
import inspect
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
        else:  # a table or a constant: its docstring, not its (long) value
            lines += [f".. autodata:: {target}", "   :no-value:", ""]
    return lines, missing


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
                "%s.__all__ names %s, which the package does not have",
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
