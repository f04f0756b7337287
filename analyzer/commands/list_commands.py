"""`gimbal-analyzer commands`: list every command and message the analyzer knows."""

from __future__ import annotations

import argparse

HELP = "list every command and message of the protocol table"
DESCRIPTION = """\
List every command of the command table (name, S_ID, CMD, parameters with
units, ranges and values), then the gimbal's feedback messages (CAN ID, length
byte, topic, fields) and the UAV status messages (CAN ID, topic, fields).

  gimbal-analyzer commands             plain list
  gimbal-analyzer commands --markdown  the same as Markdown (the manual's protocol
                                       reference is made from the same tables)
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--markdown", action="store_true", help="print the Markdown reference")


def run(args: argparse.Namespace) -> int:
    from analyzer.protocol.command_table import COMMANDS
    from analyzer.protocol.docs import TEXT_NOTE, command_reference, describe_field
    from analyzer.protocol.feedback import LAYOUTS
    from analyzer.protocol.ids import (
        CONTROL_ID,
        FEEDBACK_ID,
        FRAME_CONTROL,
        TEXT_END_ID,
        TEXT_ID,
    )
    from analyzer.protocol.uav import STATUS_FRAMES

    if args.markdown:
        print(command_reference())
        return 0
    print(f"Commands: CAN ID 0x{CONTROL_ID:08X}, TCP/UART frame type 0x{FRAME_CONTROL:02X}")
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
    print()
    print(f"Gimbal feedback: CAN ID 0x{FEEDBACK_ID:08X}, 32-byte messages in 4 x 8-byte segments")
    for layout in LAYOUTS.values():
        print(
            f"{layout.name:<18} length byte 0x{layout.length_byte:02X}  {layout.topic}  "
            f"CRC bytes {layout.crc_offset}-{layout.crc_offset + 1}"
        )
        for f in layout.layout.fields:
            print(f"    {describe_field(f)}")
    print()
    print("UAV status")
    for status in STATUS_FRAMES.values():
        print(
            f"{status.name:<18} CAN ID 0x{status.can_id:08X}  {status.topic}  {status.description}"
        )
        for f in status.layout.fields:
            print(f"    {describe_field(f)}")
    print(f"{'text':<18} CAN ID 0x{TEXT_ID:08X} start/middle, 0x{TEXT_END_ID:08X} end  /uav/text")
    print(f"    {TEXT_NOTE}")
    return 0
