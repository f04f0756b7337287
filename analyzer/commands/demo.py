"""`gimbal-analyzer demo`: simulated gimbal + ground station on a virtual bus, captured live."""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from analyzer.commands.demo_printer import DemoPrinter
from analyzer.commands.simulate import (
    add_behaviour_arguments,
    add_fault_arguments,
    add_heading_argument,
    behaviour,
    fault_config,
    seconds_value,
)
from analyzer.errors import EXIT_FAILED, SourceError, UsageError
from analyzer.live.options import add_foxglove_options
from analyzer.mcapio.write.options import add_compression_argument
from analyzer.video.spec import add_video_options

HELP = "see the whole tool work with no hardware: simulated gimbal, live decode, demo.mcap"
DESCRIPTION = """\
Starts a simulated gimbal (which also plays the UAV) and a scripted ground station
on a python-can virtual bus inside this process, captures the bus with the real
capture engine, records everything to demo.mcap and shows it live: the terminal
UI on a terminal (q quits), plain decoded lines otherwise or with --no-tui
(for 10 s unless --duration says otherwise).

The simulator injects a few faults by default (dropped, corrupted, repeated and
late feedback segments) so the diagnostics have something to show; --clean
turns them off. --sluggish, --fall-short, --ignore, --drift, --lag,
--wrong-way and --geodetic-as-airframe make a gimbal that does not always obey, for
`gimbal-analyzer analyze` and `report` to find. --heading 30 keeps the
aircraft's nose at 30 deg while it flies, so the gimbal's yaw from north
(psi) is 30 deg more than its yaw motor angle. --stick makes the ground
station drive the gimbal like a pilot's stick. Afterwards:

  gimbal-analyzer info demo.mcap       what was recorded, and the simulator's options
  gimbal-analyzer report demo.mcap     did the gimbal obey? (an HTML page)

and open demo.mcap in Foxglove (the desktop app's Open local file, or
app.foxglove.dev): map, log, plots. The recording's metadata keeps the
simulator options that made it (faults, disobedience, --heading).

With --foxglove the stream is also served live to Foxglove (ws://127.0.0.1:8765).

With --ardupilot DRIVER.lua an ArduPilot autopilot takes the ground station's
place: the Lua mount driver (made by `gimbal-analyzer export ardupilot`, or an
edited copy) runs in Lua 5.3 with ArduPilot's scripting bindings emulated, on
the same virtual CAN bus. ArduPilot's mount and camera libraries ask it for a
pilot's rates, angles in body and earth frame, a point to look at and camera
actions; its UAV status frames are the only ones (the simulator does not play
the UAV). The recording adds /ardupilot/mount (the attitude the driver reported)
and /ardupilot/targets (what the mount library asked); a script error stops the
demo (exit 1) with ArduPilot's message. --lua ardupilot runs the driver in Lua
built as ArduPilot builds it (32-bit integers and floats, at most 100 locals per
function), compiled once from lupa's sources.
"""

CHANNEL = "gimbal-demo"
DEFAULT_OUTPUT = "demo.mcap"
PLAIN_DURATION = 10.0
# Faults the demo injects unless --clean: rare enough to read, frequent enough to be seen.
DEMO_FAULTS = {"drop": 0.02, "corrupt": 0.02, "duplicate": 0.02, "delay": 0.02, "seed": 7}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "-o",
        "--output",
        default=DEFAULT_OUTPUT,
        metavar="FILE",
        help=f"recording (default {DEFAULT_OUTPUT}); a recording an earlier demo wrote is "
        "replaced, any other existing file only with --force",
    )
    parser.add_argument(
        "-f", "--force", action="store_true", help="replace an existing file demo did not write"
    )
    parser.add_argument(
        "--duration",
        type=seconds_value,
        metavar="S",
        help=f"stop after S seconds (default {PLAIN_DURATION:g} s for plain output; the UI "
        "runs until q, and with --duration its screen stays after the capture stops)",
    )
    parser.add_argument(
        "--no-tui", action="store_true", help="print decoded lines instead of the UI"
    )
    parser.add_argument(
        "--all", action="store_true", help="plain output: print every event (UAV status too)"
    )
    parser.add_argument("--clean", action="store_true", help="inject no faults")
    parser.add_argument(
        "--ardupilot",
        metavar="DRIVER.lua",
        help="run this ArduPilot Lua mount driver as the ground station, in Lua 5.3 with "
        "ArduPilot's scripting bindings emulated (see: gimbal-analyzer export ardupilot)",
    )
    parser.add_argument(
        "--lua",
        choices=("lupa", "ardupilot"),
        default="lupa",
        help="the Lua 5.3 --ardupilot runs the driver in: lupa (lupa's own: 64-bit numbers, "
        "200 locals per function; the default) or ardupilot (built as ArduPilot builds it: "
        "32-bit integers and floats, at most 100 locals per function; compiled once from "
        "lupa's sources, which needs pip to reach PyPI and a C compiler, and kept in "
        "~/.cache/gimbal-analyzer)",
    )
    add_compression_argument(parser)
    add_foxglove_options(parser)
    add_video_options(parser)  # a camera on the bench recorded next to the simulated gimbal
    simulated_camera_default(parser)
    first = len(parser._actions)
    parser.add_argument(
        "--stick",
        action="store_true",
        help="the ground station drives like a pilot: gimbal_control from a stick every "
        "50 ms, smooth movements whose speeds change in every command (with an analog "
        "stick's jitter), zeros while the stick is centred",
    )
    add_heading_argument(parser, uav_always=True)
    faults = len(parser._actions)
    add_fault_arguments(parser)
    behaviour_at = len(parser._actions)
    add_behaviour_arguments(parser)
    # The simulator's options, to be kept in the recording's metadata.
    simulator = tuple(
        SimulatorOption(a.dest, a.option_strings[-1], a.default, faults <= n < behaviour_at)
        for n, a in enumerate(parser._actions[first:], first)
    )
    parser.set_defaults(**DEMO_FAULTS, simulator_options=simulator)


def simulated_camera_default(parser: argparse.ArgumentParser) -> None:
    """Without --camera, demo's --video streams come from the simulated camera."""
    from analyzer.video.spec import SIMULATED_CAMERA

    for action in parser._actions:
        if action.dest == "camera":
            action.default = SIMULATED_CAMERA
            action.help = (
                "default sim: the simulated camera, which renders the simulated gimbal's view "
                "(zoom, thermal palette, picture-in-picture, tracking box); HOST[:PORT]: record "
                "a real camera's main/sub1/sub2/thermal next to the simulated gimbal"
            )
    parser.set_defaults(simulated_camera=True)


def simulator_metadata(args: argparse.Namespace, config: Any) -> dict[str, str]:
    """What made the simulated flight, for the recording's metadata (and `info`): the
    options as they would be typed again, and what they mean."""
    options: list[str] = ["--clean"] if args.clean else []
    for option in getattr(args, "simulator_options", ()):
        value = getattr(args, option.dest, None)
        if value == option.default or (args.clean and option.fault):
            continue
        if value is True:
            options.append(option.flag)
        elif isinstance(value, list):
            options += [f"{option.flag} {v}" for v in value]
        else:
            shown = f"{value:g}" if isinstance(value, float) else str(value)
            options.append(f"{option.flag} {shown}")
    heading = config.heading_deg
    return {
        "simulator_options": " ".join(options) or "(none)",
        "simulator_faults": config.faults.describe(),
        "simulator_gimbal": config.behaviour.describe(),
        "simulator_heading": "ahead along the orbit"
        if heading is None
        else f"{heading:g} deg from north",
    }


@dataclass(frozen=True)
class SimulatorOption:
    """One option of the simulator, as demo's metadata repeats it."""

    dest: str
    flag: str
    default: Any
    fault: bool


def _driver(args: argparse.Namespace) -> Any:
    """The --ardupilot driver, read and compiled in the --lua interpreter."""
    from analyzer.extras import ARDUPILOT, require

    require(ARDUPILOT, "--ardupilot")  # the driver runs in lupa's Lua
    from analyzer.ardupilot.live import load_driver

    def say(text: str) -> None:
        print(f"demo: {text}", file=sys.stderr, flush=True)

    return load_driver(args.ardupilot, args.lua, say)


def _autopilot(
    args: argparse.Namespace,
    spec: Any,
    config: Any,
    driver: Any,
    source: Any,
    tui: bool,
) -> Any:
    """The scene of `--ardupilot`: the simulated gimbal and the autopilot running the driver."""
    from analyzer.ardupilot.live import ArduPilotScene
    from analyzer.sim.uav import FlightPath

    def say(text: str) -> None:
        if not tui:
            print(text, flush=True)

    return ArduPilotScene(
        spec,
        config,
        driver.text,
        driver.name,
        note=source.note,
        path=FlightPath(heading_deg=args.heading),
        log=say,
        lua=driver.lua,
    )


def simulated_camera() -> tuple[Any, Any]:
    """The simulated gimbal's eye (attached once the scene exists) and the maker of the
    simulated camera's streams; neither renders anything before a stream starts."""
    from analyzer.sim.camera.eye import GimbalEye
    from analyzer.video.spec import VideoSpec

    eye = GimbalEye()

    def stream(spec: VideoSpec, thumbnail_interval: float) -> Any:
        from analyzer.sim.camera.stream import SimulatedStream  # PyAV, OpenCV: when asked

        return SimulatedStream(spec, eye, thumbnail_interval=thumbnail_interval)

    return eye, stream


def written_by_demo(path: Path) -> bool:
    """True for a recording made by `demo` itself (its metadata says so): one it may replace."""
    from analyzer.mcapio.channels import METADATA_NAME
    from analyzer.mcapio.read.reader import McapRecording

    try:
        return McapRecording(path).metadata().get(METADATA_NAME, {}).get("command") == "demo"
    except Exception:  # not a recording, or unreadable: not ours
        return False


def run(args: argparse.Namespace) -> int:
    from analyzer.commands.live_recording import Companion, open_live_recording
    from analyzer.commands.video_options import video_metadata
    from analyzer.mcapio.write.sink import recording_metadata
    from analyzer.output_file import check_output
    from analyzer.sim.transports import LinkSpec
    from analyzer.sources import open_source
    from analyzer.video.spec import VIDEO_HOLD_BACK_S, video_specs

    # a wrong --video is a usage error before anything starts; video needs the hold-back
    hold_back = VIDEO_HOLD_BACK_S if video_specs(args) else 0.0
    run_app = _monitor_app(args)
    tui = run_app is not None
    duration = args.duration if args.duration is not None else (None if tui else PLAIN_DURATION)
    if duration is not None and duration <= 0:
        raise UsageError("--duration must be a positive number of seconds")
    target = check_output(args.output, force=args.force, replaceable=written_by_demo)
    path = str(target)
    spec = LinkSpec("can", interface="virtual", channel=CHANNEL)
    _check_driver_options(args)
    config = _sim_config(args)
    driver = _driver(args) if args.ardupilot else None
    if driver is not None:
        config = replace(config, uav=False)  # the driver's status frames are the only ones
    source: Any = open_source(str(spec))
    if driver is not None:
        from analyzer.ardupilot.live import NotedSource

        source = NotedSource(source)
    printer = None if tui else DemoPrinter(sys.stdout, everything=args.all, zone=args.time_zone)
    eye, camera = simulated_camera()
    recording = open_live_recording(
        args,
        source,
        path,
        metadata=recording_metadata(
            f"demo: simulated gimbal and ground station on {spec}",
            command="demo",
            **simulator_metadata(args, config),
            **video_metadata(args),
            **({"ardupilot_driver": driver.name} if driver is not None else {}),
        ),
        hold_back=hold_back,
        sinks_after=lambda sink, video: [printer],
        simulated_camera=camera,
        replaceable=written_by_demo,
    )
    scene = _scene(args, recording, spec, config, driver, tui)
    recording.companions.append(Companion(scene.start, scene.stop))
    eye.attach(scene.gimbal)

    def first_line() -> None:
        who = (
            "simulated gimbal + UAV and a scripted ground station"
            if driver is None
            else f"simulated gimbal and ArduPilot running {driver.name}"
        )
        faults = config.faults
        print(
            f"demo: {who} on {spec}; recording {path}; faults: {faults.describe()}; {duration:g} s",
            flush=True,
        )

    result = recording.run(
        duration,
        tui=run_app,
        label=f"demo on {spec}",
        exit_when_done=args.duration is not None,
        started=first_line,
    )
    return _said_at_the_end(recording, scene, printer, tui, result)


def _monitor_app(args: argparse.Namespace) -> Any:
    """The monitor UI's runner when the demo shows it (a terminal, no --no-tui, the UI
    loads), else None: then it prints lines."""
    if args.no_tui or not (sys.stdin.isatty() and sys.stdout.isatty()):
        return None
    try:
        from analyzer.tui.app import run_app
    except ImportError:
        return None
    return run_app


def _check_driver_options(args: argparse.Namespace) -> None:
    """--lua and --stick against --ardupilot: a UsageError when they do not go together."""
    if args.lua != "lupa" and not args.ardupilot:
        raise UsageError("--lua chooses the Lua of an --ardupilot driver: give --ardupilot")
    if args.stick and args.ardupilot:
        raise UsageError(
            "--stick drives the demo's ground station, and with --ardupilot the driver is "
            "the ground station: give one of them"
        )


def _sim_config(args: argparse.Namespace) -> Any:
    """The simulated gimbal and UAV the options ask for (faults unless --clean)."""
    from analyzer.sim.engine import SimConfig
    from analyzer.sim.faults import FaultConfig

    return SimConfig(
        ranging=True,
        uav=True,
        faults=FaultConfig() if args.clean else fault_config(args),
        behaviour=behaviour(args),
        heading_deg=args.heading,
    )


def _scene(
    args: argparse.Namespace, recording: Any, spec: Any, config: Any, driver: Any, tui: bool
) -> Any:
    """The simulated gimbal with its ground station: the scripted one, or ArduPilot
    running ``driver``; on a failure the recording's source, sink and server close."""
    from analyzer.sim.ground import GroundScript, pilot_script
    from analyzer.sim.scene import Scene

    try:
        script = GroundScript(pilot_script()) if args.stick else None
        if driver is None:
            return Scene(spec, config, script=script)
        return _autopilot(args, spec, config, driver, recording.source, tui)
    except BaseException:
        recording.source.close()
        recording.sink.close()
        if recording.live is not None:
            recording.live.close()
        raise


def _said_at_the_end(
    recording: Any, scene: Any, printer: DemoPrinter | None, tui: bool, result: int
) -> int:
    """The demo's last lines (on standard error under the monitor UI); the exit code."""
    from analyzer.capture import OUTPUT_CLOSED
    from analyzer.commands.video_options import silent_streams
    from analyzer.live.attach import foxglove_summary

    capture, sink, live, video = recording.capture, recording.sink, recording.live, recording.video
    path = recording.path
    if sink.error is not None:
        raise SourceError(sink.error)
    if capture.error is not None:
        raise SourceError(
            f"{capture.error}; the recording {path} is finished and keeps everything up to then"
        )
    if capture.stop_reason == OUTPUT_CLOSED:
        return result  # the reader of the lines went away (| head): nothing more to say
    if scene.errors:
        raise SourceError(f"the simulation stopped: {scene.errors[0]}")
    stats = capture.stats
    hidden = printer.hidden if printer is not None else 0
    print(
        f"demo: {stats.frames} CAN frames, {stats.events} events, {stats.diagnostics} "
        f"diagnostics in {stats.elapsed_s:.1f} s; recorded to {path}",
        file=sys.stderr if tui else sys.stdout,
    )
    if live is not None:
        print(f"  {foxglove_summary(live)}", file=sys.stderr if tui else sys.stdout)
    if hidden:
        print(f"  ({hidden} repeated commands / UAV status lines not shown; --all shows them)")
    if not tui:
        print(f"  next: gimbal-analyzer info {path}   |   open {path} in Foxglove")
    for words in silent_streams(video) if video is not None else []:
        print(f"gimbal-analyzer demo: {words}", file=sys.stderr)  # a failure: exit 1
        if result == 0:
            result = EXIT_FAILED
    return result
