"""`gimbal-analyzer send`: encode any command of the table, print it, transmit it on request."""

from __future__ import annotations

import argparse
import re
import sys
import time
from typing import Any

from analyzer.errors import UsageError
from analyzer.protocol.command_table import BY_NAME, CommandRow
from analyzer.protocol.fields import Field
from analyzer.protocol.ids import COMPONENT_NAMES
from analyzer.terminal_text import printable

HELP = "encode a command by name and parameters; transmit it only with --to"
DESCRIPTION = """\
Encode any command of the protocol table by name and parameters. Prints the 8
CAN data bytes, the candump/cansend form and the TCP/UART frame. Nothing is
transmitted unless a destination is given with --to.

  gimbal-analyzer send --list                          every command and its options
  gimbal-analyzer send gimbal_control --help           one command's options
  gimbal-analyzer send gimbal_control --pan-speed -5   turn left at 5 deg/s (print only)
  gimbal-analyzer send specified_angle --yaw 45
  gimbal-analyzer send palette iron_red                (dual-sensor command)
  gimbal-analyzer send gimbal_control --tilt-speed 10 --repeat 50ms --count 40 \\
      --to tcp:127.0.0.1:2000
  gimbal-analyzer send look_down --to can:socketcan:vcan0

Destinations: can:INTERFACE:CHANNEL[@BITRATE] (any python-can interface),
tcp:HOST:PORT (the IDU listens on port 2000), serial:PORT[@BAUD].
A python-can virtual bus (can:virtual:...) only reaches buses in the same
process; to reach `gimbal-analyzer simulate` running in another terminal use
tcp:127.0.0.1:2000 or a vcan interface.
gimbal_control moves the gimbal only while it is repeated: use --repeat 50ms.
"""

# Unit -> the suffix a field name carries for it; an option without the suffix is an alias
# (pan_speed_dps -> --pan-speed-dps and --pan-speed; yaw_deg -> --yaw-deg and --yaw).
UNIT_SUFFIXES = {"deg/s": "_dps", "deg": "_deg", "%": "_pct", "s": "_s", "m": "_m"}
COMMON_OPTIONS = frozenset({"to", "repeat", "count", "listen", "component", "s_id", "unchecked"})


# -- options generated from the table ------------------------------------------------------------


def command_fields(rows: tuple[CommandRow, ...]) -> list[Field]:
    """Every parameter of a command name (selector first), across its table rows."""
    seen: dict[str, Field] = {}
    for row in rows:
        fields = ([row.selector] if row.selector else []) + list(row.all_fields())
        for f in fields:
            seen.setdefault(f.name, f)
    return list(seen.values())


def option_names(f: Field) -> list[str]:
    """``--pan-speed-dps`` and, where the name ends in its unit, ``--pan-speed``."""
    names = [f.name]
    suffix = UNIT_SUFFIXES.get(f.unit)
    if suffix and f.name.endswith(suffix) and len(f.name) > len(suffix):
        names.append(f.name[: -len(suffix)])
    return ["--" + n.replace("_", "-") for n in names if n not in COMMON_OPTIONS]


def field_help(f: Field) -> str:
    parts = [f.description or f.name]
    lo, hi = f.value_limits()
    unit = f" {f.unit}" if f.unit else ""
    if f.labels is not None:
        labels = ", ".join(f.labels.values())
        parts.append(f"one of: {labels}" + (f", or {f.other_label}" if f.other_label else ""))
    elif lo is not None or hi is not None:
        parts.append(f"range [{f.format_value(lo)}, {f.format_value(hi)}]{unit}")
    elif unit:
        parts.append(f"in{unit}")
    if f.default is not None:
        parts.append(f"default {f.default}")
    return "; ".join(parts)


def single_field(rows: tuple[CommandRow, ...]) -> Field | None:
    """The only parameter of a one-parameter command (it may also be given positionally)."""
    fields = command_fields(rows)
    return fields[0] if len(fields) == 1 else None


def s_id_value(text: str) -> int:
    try:
        return int(text, 0)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number (e.g. 0x1F)") from None


def _add_common(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("sending")
    group.add_argument(
        "--component",
        choices=list(COMPONENT_NAMES.values()),
        help="which component's row of the table (default: the first that has the command)",
    )
    group.add_argument(
        "--s-id", type=s_id_value, metavar="S_ID", help="the same by S_ID, e.g. 0x1F"
    )
    group.add_argument(
        "--to",
        metavar="DEST",
        help="transmit to can:INTERFACE:CHANNEL[@BITRATE], tcp:HOST:PORT or serial:PORT[@BAUD]",
    )
    group.add_argument(
        "--repeat",
        metavar="INTERVAL",
        help="send again every INTERVAL until Ctrl-C; the unit is required: 50ms or 0.5s",
    )
    group.add_argument("--count", type=int, metavar="N", help="send N times (with --repeat)")
    group.add_argument(
        "--listen",
        type=float,
        default=0.0,
        metavar="SECONDS",
        help="after sending, print the decoded replies for this long",
    )
    group.add_argument(
        "--unchecked",
        action="store_true",
        help="encode out-of-range values anyway (to test how a receiver reacts)",
    )


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--list", action="store_true", help="list every command with its options and exit"
    )
    sub = parser.add_subparsers(dest="send_command", metavar="COMMAND")
    for name, rows in BY_NAME.items():
        components = ", ".join(
            f"{COMPONENT_NAMES[r.s_id]} (S_ID 0x{r.s_id:02X} CMD 0x{r.cmd:02X})" for r in rows
        )
        p = sub.add_parser(
            name,
            help=rows[0].description,
            description=f"{rows[0].title}: {rows[0].description}\nExists for: {components}.",
            allow_abbrev=False,
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        only = single_field(rows)
        if only is not None:
            p.add_argument(
                "value", nargs="?", metavar=only.name.upper(), help=f"same as --{only.name}"
            )
        params = p.add_argument_group("parameters")
        for f in command_fields(rows):
            params.add_argument(
                *option_names(f),
                dest=f"param_{f.name}",
                metavar="VALUE" if f.labels is None else "LABEL",
                help=field_help(f).replace("%", "%%"),
            )
        _add_common(p)


def list_commands() -> str:
    lines = []
    for name, rows in BY_NAME.items():
        where = ", ".join(f"0x{r.s_id:02X}/0x{r.cmd:02X}" for r in rows)
        lines.append(f"{name}  [S_ID/CMD {where}]  {rows[0].description}")
        only = single_field(rows)
        if only is not None:
            lines.append(f"    {name} {only.name.upper()}   (positional form of --{only.name})")
        for f in command_fields(rows):
            lines.append(f"    {' / '.join(option_names(f))}: {field_help(f)}")
    return "\n".join(lines)


# -- running -------------------------------------------------------------------------------------


def parse_interval(text: str) -> float:
    """``50ms`` or ``0.05s`` -> seconds. The unit is required: a bare ``50`` is refused
    rather than guessed (50 ms and 50 s are both plausible for a repeated command)."""
    match = re.fullmatch(r"\s*(\d+(?:\.\d*)?|\.\d+)\s*(ms|s)?\s*", text)
    if not match:
        raise UsageError(f"--repeat {text!r}: expected an interval such as 50ms or 0.5s")
    if match.group(2) is None:
        number = match.group(1)
        raise UsageError(f"--repeat {text!r}: give the unit, {number}ms or {number}s")
    value = float(match.group(1)) / (1000.0 if match.group(2) == "ms" else 1.0)
    if value < 0.001:
        raise UsageError(f"--repeat {text!r}: the interval must be at least 1 ms")
    return value


def _value(f: Field, text: str) -> Any:
    """Text from the command line -> what encode_command takes for this field."""
    if f.labels is not None and re.fullmatch(r"0[xX][0-9a-fA-F]+|\d+", text):
        return int(text, 0)
    return text


def build_params(args: argparse.Namespace, rows: tuple[CommandRow, ...]) -> dict[str, Any]:
    params: dict[str, Any] = {}
    only = single_field(rows)
    for f in command_fields(rows):
        text = getattr(args, f"param_{f.name}", None)
        if text is None and only is f:
            text = getattr(args, "value", None)
        elif only is f and getattr(args, "value", None) is not None:
            raise UsageError(f"give {f.name} once: positionally or with --{f.name}")
        if text is not None:
            params[f.name] = _value(f, text)
    return params


def encode(args: argparse.Namespace) -> bytes:
    from analyzer.protocol.codec import EncodeError, encode_command

    name = args.send_command
    if args.component is not None and args.s_id is not None:
        raise UsageError("give --component or --s-id, not both")
    selector = args.s_id if args.s_id is not None else args.component
    params = build_params(args, BY_NAME[name])
    for row in BY_NAME[name]:
        variants = [f.name for fields in row.variants.values() for f in fields if f.name in params]
        if len(variants) > 1:
            raise UsageError(f"{name}: give only one of {', '.join(variants)} per command")
    try:
        return encode_command(name, s_id=selector, check_range=not args.unchecked, **params)
    except EncodeError as exc:
        raise UsageError(f"{name}: {exc}" if not str(exc).startswith(name) else str(exc)) from None


def describe(data: bytes) -> list[str]:
    from analyzer.protocol.codec import decode_command
    from analyzer.protocol.framing import wrap_control
    from analyzer.protocol.ids import CONTROL_ID
    from analyzer.protocol.types import hexstr
    from analyzer.sim.engine import describe_command

    fields, warnings = decode_command(data)
    lines = [
        f"{describe_command(fields)}   [S_ID 0x{data[0]:02X} {fields.get('component')}, "
        f"CMD 0x{data[1]:02X}]",
        f"  CAN data   {hexstr(data)}   (ID 0x{CONTROL_ID:08X}, extended)",
        f"  cansend    {CONTROL_ID:08X}#{data.hex().upper()}",
        f"  TCP frame  {hexstr(wrap_control(data))}",
    ]
    lines += [f"  warning: {w}" for w in warnings]
    return lines


def run(args: argparse.Namespace) -> int:
    if args.list:
        print(list_commands())
        return 0
    if args.send_command is None:
        raise UsageError("name a command (gimbal-analyzer send --list shows them all)")
    interval = parse_interval(args.repeat) if args.repeat is not None else None
    if args.count is not None and args.count < 1:
        raise UsageError("--count must be at least 1")
    if args.listen < 0:
        raise UsageError("--listen must not be negative")
    data = encode(args)
    for line in describe(data):
        print(line)
    if args.to is None:
        if interval is not None or args.count is not None or args.listen:
            raise UsageError("--repeat, --count and --listen need a destination: --to ...")
        print("  not sent: add --to can:INTERFACE:CHANNEL or --to tcp:HOST:PORT to transmit")
        if args.send_command == "gimbal_control":
            print("  note: the gimbal turns only while gimbal_control is repeated (--repeat 50ms)")
        return 0
    count = args.count if args.count is not None else (None if interval is not None else 1)
    if count is not None and count > 1 and interval is None:
        interval = 0.05
    return transmit(args.to, data, interval=interval, count=count, listen=args.listen)


def transmit(
    destination: str,
    data: bytes,
    *,
    interval: float | None,
    count: int | None,
    listen: float = 0.0,
) -> int:
    from analyzer.protocol.decoder import ProtocolDecoder
    from analyzer.protocol.ids import CONTROL_ID
    from analyzer.protocol.types import TOPIC_GIMBAL_ATTITUDE
    from analyzer.sim.transports import open_ground_link, parse_link

    spec = parse_link(destination)
    link = open_ground_link(spec)
    if spec.kind == "can" and spec.interface == "virtual":
        print(f"  note: {spec} reaches only buses inside this process; nothing else hears it")
    decoder = ProtocolDecoder()
    replies: list[Any] = []

    def drain(timeout: float, show: bool) -> None:
        for item in link.receive(timeout):
            for event in decoder.feed(item):
                replies.append(event)
                if show:
                    print(printable(f"  reply {event.topic} {_summary(event.fields)}"))

    sent = 0
    try:
        next_time = time.monotonic()
        while count is None or sent < count:
            link.send(CONTROL_ID, data)
            sent += 1
            if interval is None or (count is not None and sent >= count):
                break
            next_time += interval
            while (wait := next_time - time.monotonic()) > 0:
                drain(wait, show=False)
        end = time.monotonic() + listen
        while (wait := end - time.monotonic()) > 0:
            drain(wait, show=True)
    except KeyboardInterrupt:
        print(file=sys.stderr)
    finally:
        link.close()
    every = f" every {interval * 1000:g} ms" if interval is not None and sent > 1 else ""
    print(f"  sent {sent} time(s){every} to {link.name}")
    attitudes = [e for e in replies if e.topic == TOPIC_GIMBAL_ATTITUDE]
    if attitudes and not listen:
        print(printable(f"  last attitude reply: {_summary(attitudes[-1].fields)}"))
    return 0


def _summary(fields: dict[str, Any]) -> str:
    from analyzer.sim.engine import format_fields

    return format_fields(fields, frozenset({"raw", "transport", "direction"}))
