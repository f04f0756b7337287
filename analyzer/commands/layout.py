"""`gimbal-analyzer layout`: write the ready Foxglove Studio layout for recordings."""

from __future__ import annotations

import argparse
import json
import sys

HELP = "write a Foxglove Studio layout (map, camera, 3D, log, plots, modes, commands, diagnostics)"
DEFAULT_OUTPUT = "gimbal-layout.json"
DESCRIPTION = f"""\
Write a Foxglove Studio layout for gimbal-analyzer recordings:

  Map                UAV track (/uav/gps/fix) and laser-ranging target (/gimbal/ranging/fix)
  Image              the camera's thumbnails (/camera/main/thumbnail, record --video main)
                     with the tracking box, tap points and pitch / yaw / zoom drawn over them
  3D                 the aircraft, the gimbal's and camera's axes (/tf), the field of view
                     and the laser-ranging target (/gimbal/scene), following the gimbal
  Log                diagnostics (/diagnostics/log)
  Plot               gimbal pitch and yaw with the commanded pan / tilt speeds
  State Transitions  control mode, tracking and command names over time
  Plot (CAN bus)     the CAN controller's state, 0 error-active .. 3 bus-off (/can/bus_state)
  Indicator          tracking on / off
  Raw Messages       /gimbal/command
  Table              /diagnostics

Import it once in Foxglove: Layouts (left sidebar) -> Import layout, and pick
the file; it then applies to every recording you open.

  gimbal-analyzer layout                       writes {DEFAULT_OUTPUT}
  gimbal-analyzer layout -o ~/gimbal.json
  gimbal-analyzer layout -o -                  to standard output

An existing file is replaced only with --force.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "-o",
        "--output",
        default=DEFAULT_OUTPUT,
        metavar="FILE",
        help=f"file to write (default {DEFAULT_OUTPUT}; '-' for standard output)",
    )
    parser.add_argument("-f", "--force", action="store_true", help="replace FILE if it exists")


def rendered() -> str:
    from analyzer.mcapio.layout import layout

    return json.dumps(layout(), indent=2) + "\n"


def run(args: argparse.Namespace) -> int:
    text = rendered()
    if args.output == "-":
        sys.stdout.write(text)
        return 0
    from analyzer.output_file import write_output

    write_output(args.output, text, force=args.force)
    print(
        f"wrote {args.output}: in Foxglove, Layouts -> Import layout, then open a recording",
        file=sys.stderr,
    )
    return 0
