"""Sphinx configuration of the gimbal-analyzer manual.

Build it with ``pip install '.[docs]' && python -m sphinx -W --keep-going -b html docs
build/docs``. The reference pages are generated at build time from the code itself by
the small extensions in ``docs/_ext``: the command line from the argparse parsers, the
protocol from the command table, the topics from their JSON Schemas, the exit codes
from ``analyzer.errors`` and the Python API from the docstrings of ``analyzer.__all__``.
"""

from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS.parent))  # the analyzer package of this checkout
sys.path.insert(0, str(DOCS / "_ext"))

from analyzer.version import __version__  # noqa: E402

project = "gimbal-analyzer"
author = "the gimbal-analyzer authors"
copyright = "the gimbal-analyzer authors"
version = release = __version__

extensions = [
    "myst_parser",  # the pages are Markdown (MyST), as the README is
    "sphinx.ext.autodoc",  # the Python API from its docstrings
    "cli_reference",  # every sub-command and option, from the argparse parsers
    "protocol_reference",  # commands, messages, topics, schemas and exit codes
    "api_reference",  # every name of analyzer.__all__
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "_ext"]
templates_path: list[str] = []

# Options and quotes as typed: no en dash for "--force", no curly quotes around '-'.
smartquotes = False

# Indented blocks are commands and their output (the doc tests run them): no colouring.
highlight_language = "text"

myst_enable_extensions = ["colon_fence", "deflist"]
myst_heading_anchors = 3  # [text](page.md#a-heading) links to a heading of a page

html_theme = "furo"
html_title = f"gimbal-analyzer {__version__}"
html_static_path: list[str] = []
html_show_sourcelink = False

autodoc_member_order = "bysource"
autodoc_typehints = "description"

nitpicky = False
