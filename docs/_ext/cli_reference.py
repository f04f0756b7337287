"""Sphinx directive ``gimbal-cli``: every sub-command and option, from the argparse parsers.

The reference is made from ``analyzer.cli.build_parser()`` at build time, so it says
what ``--help`` says and cannot go stale: per command its one-line help, usage, the
description and examples exactly as ``--help`` prints them (and the words of an option
group, such as camera video), and every argument as a
Sphinx ``option`` (so ``{option}`gimbal-analyzer decode --format``` links to it). An
argument without a help text is a warning, which ``-W`` makes a failed build.
"""

from __future__ import annotations

import argparse
import os
import re
from collections.abc import Iterator

from code_dependencies import note_code_dependencies
from docutils import nodes
from docutils.statemachine import StringList
from sphinx.application import Sphinx
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective
from sphinx.util.nodes import nested_parse_with_titles

logger = logging.getLogger(__name__)
WIDTH = "88"  # the terminal width the usage and descriptions are laid out for

_RST_SPECIAL = re.compile(r"([\\`*_|\[\]<>:])")


def rst_text(text: str) -> str:
    """Plain text as reStructuredText that shows it as it is (markup characters escaped)."""
    return _RST_SPECIAL.sub(r"\\\1", " ".join(text.split()))


def walk(
    parser: argparse.ArgumentParser, prog: str = "gimbal-analyzer", summary: str = ""
) -> Iterator[tuple[str, str, argparse.ArgumentParser]]:
    """(command line, one-line help, parser) of the program and of every sub-command,
    depth first, in the order ``--help`` lists them."""
    yield prog, summary, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {choice.dest: choice.help or "" for choice in action._choices_actions}
            for name, sub in action.choices.items():
                yield from walk(sub, f"{prog} {name}", helps.get(name, ""))


def documented_actions(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    """The arguments ``--help`` shows (sub-command choosers are sections of their own)."""
    return [
        action
        for action in parser._actions
        if action.help != argparse.SUPPRESS and not isinstance(action, argparse._SubParsersAction)
    ]


def invocation(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    """How ``--help`` names the argument: ``-o FILE, --output FILE``, ``file``."""
    formatter = parser._get_formatter()
    return formatter._format_action_invocation(action)


def help_text(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    """The argument's help with ``%(default)s`` and the like filled in."""
    if not action.help:
        return ""
    return parser._get_formatter()._expand_help(action)


def _literal(text: str) -> list[str]:
    lines = text.rstrip().splitlines()
    return ["::", "", *[f"   {line}" if line.strip() else "" for line in lines], ""]


def command_rst(
    command: str, summary: str, parser: argparse.ArgumentParser, missing: list[str]
) -> list[str]:
    """The section of one command, as reStructuredText lines (arguments without a help
    text are added to ``missing``)."""
    label = "cli-" + (command.split(" ", 1)[1].replace(" ", "-") if " " in command else "main")
    title = f"``{command}``" if " " in command else "``gimbal-analyzer``"
    out = [f".. _{label}:", "", title, "-" * len(title), ""]
    if summary and " " in command:
        out += [rst_text(summary[:1].upper() + summary[1:]) + ".", ""]
    out += [f".. program:: {command}", ""]
    usage = parser.format_usage().replace("usage: ", "", 1)
    out += _literal(usage.replace("\n" + " " * len("usage: "), "\n"))
    formatter = parser._get_formatter()
    for text in (parser.description, parser.epilog):
        if text and text.strip():
            out += _literal(formatter._format_text(text))
    for group in parser._action_groups:  # an option group's own words (camera video)
        if group.description and group.description.strip():
            out += [f"{rst_text(group.title or '')}:", ""]
            out += _literal(formatter._format_text(group.description))
    for action in documented_actions(parser):
        words = help_text(parser, action)
        if not words:
            missing.append(f"{command} {invocation(parser, action)}")
        out += [f".. option:: {invocation(parser, action)}", ""]
        out += [f"   {rst_text(words)}", ""] if words else []
    return out


def reference_rst(missing: list[str]) -> list[str]:
    """Every command's section (arguments without a help text are added to ``missing``)."""
    from analyzer.cli import build_parser

    previous = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = WIDTH  # argparse lays out help for the terminal's width
    try:
        lines: list[str] = []
        for command, summary, parser in walk(build_parser()):
            lines += command_rst(command, summary, parser, missing)
        return lines
    finally:
        if previous is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = previous


class CommandLineReference(SphinxDirective):
    """``.. gimbal-cli::``: the whole command-line reference."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        note_code_dependencies(self.env)
        container = nodes.section()
        container.document = self.state.document
        missing: list[str] = []
        lines = StringList(reference_rst(missing), "<gimbal-cli>")
        nested_parse_with_titles(self.state, lines, container)
        for argument in missing:
            logger.warning(
                "%s has no help text: say what it does in add_argument(help=...)",
                argument,
                location=self.get_location(),
            )
        return list(container.children)


def setup(app: Sphinx) -> dict[str, object]:
    app.add_directive("gimbal-cli", CommandLineReference)
    return {"version": "1", "parallel_read_safe": True}
