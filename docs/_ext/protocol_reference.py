"""Sphinx directives that write reference pages from the code's own tables at build time.

- ``gimbal-protocol``: every command, feedback and UAV message, from the command table
  (``analyzer.protocol.docs.reference_body``, the text ``commands --markdown`` prints);
- ``gimbal-topics``: every topic's fields and its JSON Schema (``analyzer.protocol.schema``,
  the schemas ``gimbal-analyzer schemas`` writes);
- ``gimbal-exit-codes``: the exit codes of ``analyzer.errors`` (the table ``--help`` shows).

Each renders Markdown and parses it as the MyST page it stands in, so one generator
serves the command line and the manual.
"""

from __future__ import annotations

import json
from typing import Any

from code_dependencies import note_code_dependencies
from docutils import nodes
from docutils.statemachine import StringList
from sphinx.application import Sphinx
from sphinx.util.docutils import SphinxDirective


def cell(text: object) -> str:
    """Text for one line of Markdown (a table cell, a list item): ``|`` escaped."""
    return " ".join(str(text).split()).replace("|", "\\|")


def _type_of(spec: dict[str, Any]) -> str:
    kind = spec.get("type", "")
    if isinstance(kind, list):
        kind = " or ".join(kind)
    if kind == "array" and isinstance(spec.get("items"), dict) and "type" in spec["items"]:
        kind = f"array of {spec['items']['type']}"
    return str(kind) or "any"


def _values(spec: dict[str, Any]) -> str:
    """What a field may hold beyond its type: const, enum, pattern, bounds."""
    parts = []
    if "const" in spec:
        parts.append(f"always `{spec['const']}`")
    if "enum" in spec:
        parts.append(
            "one of " + ", ".join(f"`{value}`" if value else '`""`' for value in spec["enum"])
        )
    if "minimum" in spec or "maximum" in spec:
        parts.append(f"{spec.get('minimum', '')}..{spec.get('maximum', '')}")
    if "pattern" in spec:
        parts.append(f"matches `{spec['pattern']}`")
    return "; ".join(parts)


def topics_markdown() -> str:
    """A section per topic: what it is, a list of its fields, its JSON Schema."""
    from analyzer.protocol.schema import schema_filename, topic_schemas

    lines: list[str] = []
    for topic, schema in topic_schemas().items():
        required = set(schema.get("required", []))
        lines += [f"## `{topic}`", "", cell(schema.get("description", "")), ""]
        lines += [
            f"Schema: `schemas/{schema_filename(topic)}` (title *{schema.get('title', '')}*); "
            "fields marked **required** are in every event.",
            "",
        ]
        for name, spec in schema.get("properties", {}).items():
            kind = _type_of(spec) + (", **required**" if name in required else "")
            words = "; ".join(w for w in (spec.get("description", ""), _values(spec)) if w)
            lines.append(f"- `{name}` ({kind})" + (f": {cell(words)}" if words else ""))
        lines += ["", "```json", json.dumps(schema, indent=2), "```", ""]
    return "\n".join(lines)


def exit_codes_markdown() -> str:
    from analyzer.errors import EXIT_CODES

    lines = ["| code | meaning |", "|---|---|"]
    lines += [f"| {code} | {cell(words)} |" for code, words in EXIT_CODES]
    return "\n".join(lines)


def protocol_markdown() -> str:
    from analyzer.protocol.docs import reference_body

    return reference_body()


class MarkdownFromCode(SphinxDirective):
    """Parses the Markdown a function of the code returns, in place of the directive."""

    has_content = False
    render = staticmethod(protocol_markdown)

    def run(self) -> list[nodes.Node]:
        note_code_dependencies(self.env)
        container = nodes.section()
        container.document = self.state.document
        text = StringList(self.render().splitlines(), f"<{self.name}>")
        self.state.nested_parse(text, 0, container, match_titles=True)
        return list(container.children)


class ProtocolReference(MarkdownFromCode):
    render = staticmethod(protocol_markdown)


class TopicsReference(MarkdownFromCode):
    render = staticmethod(topics_markdown)


class ExitCodesReference(MarkdownFromCode):
    render = staticmethod(exit_codes_markdown)


def setup(app: Sphinx) -> dict[str, object]:
    app.add_directive("gimbal-protocol", ProtocolReference)
    app.add_directive("gimbal-topics", TopicsReference)
    app.add_directive("gimbal-exit-codes", ExitCodesReference)
    return {"version": "1", "parallel_read_safe": True}
