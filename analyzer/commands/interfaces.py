"""`gimbal-analyzer interfaces`: the CAN adapters and serial ports here, and how to record each."""

from __future__ import annotations

import argparse
import json
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from analyzer.sources.detect import Inventory, SerialPort

HELP = "list the CAN adapters and serial ports of this machine, with the --source for each"
DESCRIPTION = """\
List the CAN adapters python-can finds (SocketCAN interfaces, up or down, PCAN,
Kvaser, Vector, ...) and the serial ports pyserial finds (with USB vendor:product,
serial number and the stable /dev/serial/by-id name), each with the --source
line that records from it.

  gimbal-analyzer interfaces          the list, with a --source line each
  gimbal-analyzer interfaces --json   the same as one JSON object

The gimbal's CAN bus runs at 1 Mbit/s: "@1000000" in a can: source says so (it
is also the default). Captures never transmit; where the adapter has a
listen-only mode it is requested. USB serial adapters are given by their
/dev/serial/by-id name, which stays the same when the adapter is plugged in
again (ttyACM0 may come back as ttyACM1), so a capture finds it again.
Software buses (virtual, udp_multicast) and socketcand servers on the network
are not searched.
"""

NOTES = (
    "@1000000 is the gimbal's CAN bitrate (also the default); give another only for another bus.",
    "Nothing is ever transmitted: where the adapter has a listen-only mode it is "
    "requested, so it does not even acknowledge frames.",
    "A capture whose adapter is unplugged goes on and reopens it when it is back; "
    "the /dev/serial/by-id names survive a replug.",
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def _usb_words(port: SerialPort) -> str:
    parts = [port.description or port.product or ""]
    if port.usb:
        parts.append(f"USB {port.usb}")
    if port.serial_number:
        parts.append(f"serial {port.serial_number}")
    if port.manufacturer and port.manufacturer not in parts[0]:
        parts.append(port.manufacturer)
    return "  ".join(p for p in parts if p)


def render(inventory: Inventory) -> str:
    """The inventory as the text ``interfaces`` prints."""
    from analyzer.sources.socketcan_links import bring_up

    lines = ["CAN adapters (python-can):"]
    if not inventory.can:
        lines.append("  none found (a USB slcan adapter shows up among the serial ports)")
    for adapter in inventory.can:
        state = f" ({adapter.state})" if adapter.state else ""
        lines.append(f"  {adapter.interface} {adapter.channel}{state}")
        lines.append(f"      --source {adapter.source}")
        lines.append(f"      listen-only: {adapter.listen_only}")
        if adapter.state == "down":
            lines.append(f"      the link is down: {bring_up(adapter.channel)}")
    lines += ["", "Serial ports (pyserial):"]
    if not inventory.serial:
        lines.append("  none found")
    for port in inventory.serial:
        words = _usb_words(port)
        lines.append(f"  {port.device}" + (f"  {words}" if words else ""))
        if port.stable_path:
            lines.append(f"      stable name {port.stable_path}")
        if port.slcan:
            lines.append(f"      {port.slcan}: --source {port.slcan_source}  (listen-only)")
            lines.append(f"      as a plain UART: --source {port.serial_source}")
        else:
            lines.append(f"      the gimbal's UART: --source {port.serial_source}")
            if port.usb:
                lines.append(f"      if it is an slcan CAN adapter: --source {port.slcan_source}")
    if inventory.problems:
        lines += ["", "Not searched completely:"]
        lines += [f"  {problem}" for problem in inventory.problems]
    lines += ["", *NOTES]
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    from analyzer.sources.detect import detect

    inventory = detect()
    if args.json:
        print(json.dumps(inventory.to_dict(), indent=2))
    else:
        print(render(inventory))
    return 0
