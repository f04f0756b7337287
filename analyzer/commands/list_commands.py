"""`gimbal-analyzer commands`: list every command and message the analyzer knows."""

from __future__ import annotations

import argparse

HELP = "list every command and message of the protocol table"
DESCRIPTION = """\
List every command of the command table (name, S_ID, CMD, parameters with
units, ranges and values) and the feedback / UAV status messages.

  gimbal-analyzer commands             plain list
  gimbal-analyzer commands --markdown  the reference in docs/protocol.md
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--markdown", action="store_true", help="print the Markdown reference")


def run(args: argparse.Namespace) -> int:
    from analyzer.protocol.command_table import COMMANDS
    from analyzer.protocol.docs import command_reference, describe_field

    if args.markdown:
        print(command_reference())
        return 0
    for row in COMMANDS:
        print(f"{row.name:<18} S_ID 0x{row.s_id:02X} CMD 0x{row.cmd:02X}  {row.title}")
        fields = ([row.selector] if row.selector else []) + list(row.params)
        for f in fields:
            print(f"    {describe_field(f, 2)}")
        if row.selector is not None:
            for key, variant in row.variants.items():
                label = (row.selector.labels or {}).get(key, str(key))
                for f in variant:
                    print(f"    when {row.selector.name}={label}: {describe_field(f, 2)}")
    return 0
