"""`gimbal-analyzer simulate`: a simulated gimbal (and UAV) on a CAN bus, TCP or a serial port."""

from __future__ import annotations

import argparse
import ipaddress
import math
import sys
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from analyzer.errors import SourceError, UsageError
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.faults import FaultConfig

if TYPE_CHECKING:
    from analyzer.sim.engine import SimulatedGimbal
    from analyzer.sim.transports import LinkSpec

HELP = "run a simulated gimbal that answers commands (CAN, TCP in the IDU's role, serial)"
DESCRIPTION = """\
A simulated gimbal for testing analyzers and ground stations without hardware.
It decodes the commands it receives (gimbal_control speeds turn it, specified_angle
moves it at 60 deg/s, look_down / forward / zoom / tracking act) and answers with
attitude feedback every 500 ms as four 8-byte segments with a correct CRC.

  gimbal-analyzer simulate --on tcp:127.0.0.1:2000      be the IDU on loopback port 2000
  gimbal-analyzer simulate --on can:socketcan:vcan0 --uav --ranging
  gimbal-analyzer simulate --on tcp:2000 --drop 0.05 --corrupt 0.02 --seed 1
  gimbal-analyzer simulate --stop-feedback-at 10 --stop-feedback-for 3
  gimbal-analyzer simulate --sluggish 0.4 --ignore tracking --drift 2
  gimbal-analyzer simulate --sluggish 0 --start-pitch -45 --start-yaw 120   frozen, off centre
  gimbal-analyzer simulate --heading 30 --geodetic-as-airframe

Then, in another terminal, e.g.:
  gimbal-analyzer monitor --source tcp:127.0.0.1:2000
  gimbal-analyzer send gimbal_control --tilt-speed 10 --repeat 50ms --to tcp:127.0.0.1:2000

Links: can:INTERFACE:CHANNEL[@BITRATE] (python-can; can:virtual:NAME only reaches
buses in the same process), tcp:[HOST:]PORT (a server on 127.0.0.1 unless a host
is given), serial:PORT[@BAUD]. Fault rates are per feedback segment (0.05 or 5%).
"""

DEFAULT_LINK = "can:virtual:gimbal-demo"


def rate_value(text: str) -> float:
    """``0.05`` or ``5%`` -> 0.05."""
    try:
        value = float(text[:-1]) / 100 if text.endswith("%") else float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a rate (e.g. 0.05 or 5%)") from None
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"{text!r}: a rate must be between 0 and 1 (0%..100%)")
    return value


def seconds_value(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"{text!r}: must not be negative")
    return value


def add_fault_arguments(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("fault injection (per feedback segment)")
    for kind, what in (
        ("drop", "leave a segment out"),
        ("corrupt", "flip bits in a segment (the CRC then fails)"),
        ("duplicate", "send a segment twice"),
        ("delay", "send a segment (and those after it) late"),
    ):
        group.add_argument(
            f"--{kind}", type=rate_value, default=0.0, metavar="RATE", help=f"{what}; e.g. 0.05"
        )
    group.add_argument(
        "--delay-by", type=seconds_value, default=0.3, metavar="S", help="how late (default 0.3 s)"
    )
    group.add_argument(
        "--stop-feedback-at",
        type=seconds_value,
        metavar="S",
        help="stop all feedback S seconds after the start ...",
    )
    group.add_argument(
        "--stop-feedback-for",
        type=seconds_value,
        default=3.0,
        metavar="S",
        help="... for S seconds (default 3)",
    )
    group.add_argument("--seed", type=int, help="seed of the fault generator (repeatable runs)")


def heading_value(text: str) -> float:
    """``30`` -> 30.0 (degrees clockwise from north, taken modulo 360)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an angle in degrees") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not an angle in degrees")
    return value % 360.0


def angle_value(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not an angle in degrees")
    return value


def add_heading_argument(parser: argparse.ArgumentParser, *, uav_always: bool = False) -> None:
    """--heading; ``uav_always``: the command always plays the UAV (demo has no --uav)."""
    flying = (
        "the simulated aircraft keeps its nose that way while it flies (default: ahead "
        "along the orbit)"
        if uav_always
        else "with --uav the aircraft keeps its nose that way while it flies (default: 0 "
        "alone, ahead along the orbit with --uav)"
    )
    parser.add_argument(
        "--heading",
        type=heading_value,
        metavar="DEG",
        help="the aircraft's heading, degrees from north: the gimbal's yaw from north (psi) "
        f"is then the heading plus its yaw motor angle, as on a real aircraft; {flying}",
    )


def add_behaviour_arguments(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("disobedience (what `gimbal-analyzer analyze` finds)")
    group.add_argument(
        "--sluggish",
        type=rate_value,
        metavar="FACTOR",
        help="move at this fraction of the asked speeds and slew rate (e.g. 0.4)",
    )
    group.add_argument(
        "--fall-short",
        type=rate_value,
        metavar="FRACTION",
        help="stop this fraction of the way to a target angle (e.g. 0.7)",
    )
    group.add_argument(
        "--ignore",
        action="append",
        default=[],
        metavar="COMMAND",
        help="do not act on this command name (repeatable), e.g. tracking",
    )
    group.add_argument(
        "--drift",
        type=seconds_value,
        default=0.0,
        metavar="S",
        help="keep turning S seconds after gimbal_control commands stop or ask for 0, 0",
    )
    group.add_argument(
        "--lag",
        type=seconds_value,
        default=0.0,
        metavar="S",
        help="act on every command S seconds after it came (e.g. 0.3)",
    )
    group.add_argument(
        "--wrong-way",
        action="store_true",
        help="turn the other way for gimbal_control speeds (pan and tilt reversed)",
    )
    group.add_argument(
        "--geodetic-as-airframe",
        action="store_true",
        help="take specified_angle yaw targets of the geodetic frame (DATA4 not 1) from the "
        "airframe's nose instead of from north",
    )


def behaviour(args: argparse.Namespace) -> Behaviour:
    from analyzer.protocol.command_table import COMMAND_NAMES

    unknown = [name for name in args.ignore if name not in COMMAND_NAMES]
    if unknown:
        raise UsageError(
            f"--ignore {unknown[0]}: not a command name (see 'gimbal-analyzer commands')"
        )
    return Behaviour(
        speed=1.0 if args.sluggish is None else args.sluggish,
        reach=1.0 if args.fall_short is None else args.fall_short,
        ignore=frozenset(args.ignore),
        drift_s=args.drift,
        geodetic_as_airframe=args.geodetic_as_airframe,
        lag_s=args.lag,
        wrong_way=args.wrong_way,
    )


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--on",
        default=DEFAULT_LINK,
        metavar="LINK",
        help=f"where to speak the protocol (default {DEFAULT_LINK})",
    )
    parser.add_argument(
        "--ranging",
        action="store_true",
        help="also send laser-ranging feedback: every 2 s, in the place of an attitude "
        "message (one feedback message every 500 ms in all)",
    )
    parser.add_argument(
        "--uav", action="store_true", help="also play the UAV: GPS, altitude, attitude, text"
    )
    parser.add_argument(
        "--gimbal-type", type=int, default=1, metavar="N", help="gimbal type of Note 1 (default 1)"
    )
    parser.add_argument(
        "--duration", type=seconds_value, metavar="S", help="stop after S seconds (default: Ctrl-C)"
    )
    parser.add_argument(
        "--camera-port",
        type=int,
        metavar="PORT",
        help="also serve the simulated camera (the gimbal's view: zoom, thermal palette, "
        "picture-in-picture) over RTSP on 127.0.0.1:PORT at the document's paths "
        "(/cam/realmonitor?channel=1&subtype=0|1|2, user admin, password admin; 0: a free "
        "port); needs GStreamer's RTSP server (Debian: python3-gi gir1.2-gst-rtsp-server-1.0 "
        "gstreamer1.0-rtsp)",
    )
    parser.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        help="print only the start and the end, not each command",
    )
    for axis, what, limits in (
        ("pitch", "pitch", "-110..60"),
        ("yaw", "yaw motor angle from the nose", "+-170"),
    ):
        parser.add_argument(
            f"--start-{axis}",
            type=angle_value,
            default=0.0,
            metavar="DEG",
            help=f"the {what} the gimbal starts at (default 0; within {limits}): a gimbal "
            "on the bench is wherever it was left",
        )
    add_heading_argument(parser)
    add_fault_arguments(parser)
    add_behaviour_arguments(parser)


def fault_config(args: argparse.Namespace) -> FaultConfig:
    return FaultConfig(
        drop=args.drop,
        corrupt=args.corrupt,
        duplicate=args.duplicate,
        delay=args.delay,
        delay_s=args.delay_by,
        stop_at=args.stop_feedback_at,
        stop_for=args.stop_feedback_for,
        seed=args.seed,
    )


def _is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _camera(args: argparse.Namespace, gimbal: Any, link: Any) -> Any:
    """The simulated camera served over RTSP (--camera-port), started; None without."""
    if args.camera_port is None:
        return None
    if not 0 <= args.camera_port < 65536:
        link.close()
        raise UsageError(f"--camera-port must be 0..65535, not {args.camera_port}")
    from analyzer.sim.camera.eye import GimbalEye
    from analyzer.sim.camera.rtsp import CameraServerError, RtspCamera

    eye = GimbalEye()
    eye.attach(gimbal)
    try:
        return RtspCamera(eye, args.camera_port)
    except CameraServerError as exc:
        link.close()
        raise SourceError(f"--camera-port: {exc}") from None


def _say_what_runs(
    args: argparse.Namespace,
    spec: LinkSpec,
    link_name: str,
    gimbal: SimulatedGimbal,
    say: Callable[[str], None],
) -> None:
    """The simulator's first lines: what it is, where it listens and what it sends."""
    from analyzer.protocol.feedback import GIMBAL_TYPES
    from analyzer.protocol.ids import CONTROL_ID, FEEDBACK_ID

    kind = GIMBAL_TYPES[args.gimbal_type]
    say(f"simulated gimbal, type {args.gimbal_type} ({kind}), on {link_name}")
    if spec.kind == "can":
        say(
            f"  commands on CAN ID 0x{CONTROL_ID:08X}; attitude feedback every 500 ms on "
            f"0x{FEEDBACK_ID:08X} (4 segments of 8 bytes)"
        )
        if spec.interface == "virtual":
            say(
                "  note: a python-can virtual bus only reaches this process; other programs reach "
                "the simulator through --on tcp:127.0.0.1:2000 or a vcan interface"
            )
    else:
        role = "as the IDU (TCP server)" if spec.kind == "tcp" else "on the UART"
        say(f"  {role}: reads 0x0A control frames, answers with 0x0C attitude frames every 500 ms")
        if spec.kind == "tcp" and not _is_loopback(spec.host):
            say(f"  warning: {spec.host} is not a loopback address: reachable from the network")
    say(
        "  ranging feedback: "
        + ("every 2 s, in place of an attitude message" if args.ranging else "off (--ranging)")
    )
    say(
        "  UAV: "
        + (
            "GPS 5 Hz, altitude 5 Hz, attitude 10 Hz, a text every 5 s, orbiting 150 m"
            if args.uav
            else "off (--uav); UAV frames received are used for heading and ranging"
        )
    )
    if args.heading is not None:
        say(f"  aircraft heading: {args.heading:g} deg (psi = heading + yaw motor angle)")
    if args.start_pitch or args.start_yaw:
        model = gimbal.model
        say(f"  starts at pitch {model.pitch_deg:g}, yaw motor {model.motor_yaw_deg:g}")


def run(args: argparse.Namespace) -> int:
    from analyzer.protocol.feedback import GIMBAL_TYPES
    from analyzer.sim.engine import SimConfig, SimulatedGimbal
    from analyzer.sim.runner import SimulatorRunner
    from analyzer.sim.transports import open_gimbal_link, parse_link

    if args.gimbal_type not in GIMBAL_TYPES:
        valid = ", ".join(f"{k} ({v})" for k, v in GIMBAL_TYPES.items())
        raise UsageError(f"--gimbal-type {args.gimbal_type}: valid: {valid}")
    spec = parse_link(args.on)

    def say(text: str) -> None:
        print(text, flush=True)

    start = time.monotonic()
    link = open_gimbal_link(spec, log=lambda text: say(f"[{time.monotonic() - start:7.2f}] {text}"))
    config = SimConfig(
        gimbal_type=args.gimbal_type,
        ranging=args.ranging,
        uav=args.uav,
        faults=fault_config(args),
        behaviour=behaviour(args),
        heading_deg=args.heading,
        attitude=(args.start_pitch, args.start_yaw),
    )
    gimbal = SimulatedGimbal(start, config)
    camera = _camera(args, gimbal, link)
    _say_what_runs(args, spec, link.name, gimbal, say)
    say(f"  faults: {config.faults.describe()}")
    say(f"  behaviour: {config.behaviour.describe()}")
    if camera is not None:
        say(
            f"  camera: rtsp://admin:admin@127.0.0.1:{camera.port}/cam/realmonitor?channel=1&"
            "subtype=0 (main), 1 (sub1), 2 (thermal); `record --video main --camera "
            f"127.0.0.1:{camera.port}` records it"
        )
        camera.start()
    say(f"  stops after {args.duration:g} s" if args.duration is not None else "  Ctrl-C to stop")
    runner = SimulatorRunner(gimbal, link, log=None if args.quiet else say)
    try:
        runner.run(args.duration)
    except KeyboardInterrupt:
        print(file=sys.stderr)
    finally:
        if camera is not None:
            camera.stop()
        link.close()
    model = gimbal.model
    say(f"done: {model.commands} command(s) acted on, {model.ignored} ignored")
    say(f"  {gimbal.state_line()}")
    say(f"  {gimbal.counts_line()}")
    return 0
