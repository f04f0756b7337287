"""The soundness harness: seeded random scenarios, and whether their verdicts are right.

A scenario is a simulated gimbal, healthy or with one fault model, started anywhere in
its range, driven by a random ground-station script (``tests.soundness_scripts``) or
by the bench check, over a link with the demo's faults (dropped, damaged, repeated and
late feedback segments) in three scenarios of four, the feedback stopping for 1 to 4 s
in one of four, and cut at a random moment. It is
judged three ways, each as a user meets it:

- ``analyze``: the findings ``analyze`` gives of the bus (the Python API's ``analyze``
  over the decoded events, as of a candump of it);
- ``monitor``: the verdicts the monitor's "Did it obey?" panel counts
  (``MonitorState`` fed by a live pipeline with the analysis stage, batch by batch);
- ``check``: the steps of ``check`` on the simulated bench (``analyzer.check.offline``)
  and the findings of its recording.

A healthy gimbal must get no ``partial`` / ``not_obeyed`` finding and no failed step (a
false alarm); the ``feedback`` step, which judges the link itself, is left out when the
link has faults. A faulty gimbal must be named: a finding (or a step's sentence) says
what the fault does (a miss otherwise). ``benchmarks/verdict_soundness.py`` runs many;
``tests/test_verdict_soundness.py`` a fixed few.
"""

from __future__ import annotations

import random
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from analyzer.analysis.stage import Analysis
from analyzer.api.analysis import analyze
from analyzer.check.offline import SimulatedBench
from analyzer.check.steps import STEPS, Options
from analyzer.commands.demo import DEMO_FAULTS
from analyzer.pipeline import Batch, Pipeline
from analyzer.protocol.check_fields import FAIL
from analyzer.protocol.types import TOPIC_ANALYSIS_RESPONSE, CanFrame
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.engine import SimConfig
from analyzer.sim.faults import FaultConfig
from analyzer.sim.ground import Step
from analyzer.sim.model import MAX_ZOOM, ZOOM_RATE
from analyzer.sim.offline import run_offline
from analyzer.tui.state import MonitorState
from tests.soundness_scripts import PITCH_RANGE, YAW_RANGE, random_script

START = 1_715_680_800.0
MODELS = (
    "frozen",
    "sluggish",
    "lag",
    "wrong_way",
    "drift",
    "ignores",
    "geodetic_as_airframe",
    "zoom_ignored",
)
HEALTHY = "healthy"
BAD = frozenset({"partial", "not_obeyed"})
# What a finding (or a failed step) says when it names the fault; ``lag`` is named by
# any verdict's sentence (a late gimbal may still obey), the others by a bad verdict.
SIGNS: dict[str, tuple[str, ...]] = {
    "frozen": ("never moved", "hardly moved", "did not move"),
    "sluggish": ("sluggish", "still on its way", "slower than the minimum", "more than 25 % off"),
    "lag": (" late",),  # "it followed about 0.6 s late", "it began to move about 0.6 s late"
    "wrong_way": ("the wrong way",),
    "drift": ("still moving",),
    "ignores": ("never moved", "hardly moved", "did not move", "stayed off", "stayed on"),
    "geodetic_as_airframe": ("as if DATA4 were 1",),
    "zoom_ignored": ("kept its scale",),
}
# The commands an ``ignores`` gimbal may ignore, and the episode that shows it.
IGNORED = {
    "specified_angle": "pitch",
    "look_down": "look_down",
    "forward": "forward",
    "gimbal_control": "long_stick",
    "tracking": "tracking",
    "tracking_stop": "tracking",
}
# The check's steps that can show a fault (a subset of steps always holds one of them).
MOVES = ("forward", "pitch_angle", "yaw_airframe", "yaw_geodetic", "look_down")
SPEEDS = ("pan_speed", "tilt_speed")
SHOWN_BY: dict[str, tuple[str, ...]] = {
    "frozen": MOVES + SPEEDS,
    "sluggish": MOVES + SPEEDS,
    "lag": MOVES + SPEEDS,
    "wrong_way": SPEEDS,
    "drift": SPEEDS,
    "geodetic_as_airframe": ("yaw_geodetic",),
    "specified_angle": ("pitch_angle", "yaw_airframe", "yaw_geodetic"),
    "look_down": ("look_down",),
    "forward": ("forward",),
    "gimbal_control": SPEEDS,
    "tracking": ("tracking",),
    "tracking_stop": ("tracking",),
}
OUTAGES = 0.25  # the share of scenarios whose feedback stops for 1 to 4 s at some moment
SEEN_FOR_S = 8.0  # a fault's first episode is followed by this much of the run, at least
LONGEST_S = 60.0  # a script is written this long, then cut


@dataclass(frozen=True)
class Scenario:
    """One seeded scenario: ``model`` (healthy or a fault), judged ``where`` (analyze,
    check or camera)."""

    seed: int
    model: str
    where: str

    def __str__(self) -> str:
        return f"{self.where} {self.model} seed {self.seed}"


@dataclass
class Outcome:
    """What a scenario gave: the false verdicts of a healthy gimbal (``alarms``, per
    view), whether a fault was named (None for a healthy one), and what was run."""

    scenario: Scenario
    alarms: dict[str, list[str]] = field(default_factory=dict)
    named: bool | None = None
    said: list[str] = field(default_factory=list)  # every bad verdict, for a miss's reader
    about: str = ""


def behaviour_for(model: str, rng: random.Random) -> tuple[Behaviour, str]:
    """The simulated gimbal of ``model`` (random parameters) and what it ignores."""
    if model == HEALTHY:
        lag = rng.choice((0.0, rng.uniform(0.02, 0.2)))  # a healthy gimbal's latency
        return Behaviour(lag_s=lag), ""
    if model == "frozen":
        return Behaviour(speed=0.0), ""
    if model == "sluggish":
        return Behaviour(speed=rng.uniform(0.25, 0.45)), ""
    if model == "lag":
        return Behaviour(lag_s=rng.uniform(0.3, 0.8)), ""
    if model == "wrong_way":
        return Behaviour(wrong_way=True), ""
    if model == "drift":
        return Behaviour(drift_s=rng.uniform(1.5, 3.0)), ""
    if model == "ignores":
        name = rng.choice(sorted(IGNORED))
        return Behaviour(ignore=frozenset({name})), name
    if model == "geodetic_as_airframe":
        return Behaviour(geodetic_as_airframe=True), ""
    if model == "zoom_ignored":
        return Behaviour(ignore=frozenset({"zoom"})), "zoom"
    raise ValueError(f"no fault model {model!r}")


def first_episode(model: str, ignored: str) -> str | None:
    """The episode a fault's scenario starts with, so that the fault can show."""
    if model in ("sluggish", "lag", "wrong_way"):
        return "long_stick"
    if model == "drift":  # the stick let go at speed: it drifts on at that speed
        return "released_stick"
    if model == "frozen":
        return "pitch"
    if model == "geodetic_as_airframe":
        return "yaw_geodetic"
    if model == "ignores":
        return IGNORED[ignored]
    return None


def config_for(scenario: Scenario) -> tuple[SimConfig, random.Random, str]:
    rng = random.Random(f"{scenario.where} {scenario.model} {scenario.seed}")
    behaviour, ignored = behaviour_for(scenario.model, rng)
    faulty = rng.random() < 0.75
    link: dict[str, Any] = {**DEMO_FAULTS, "seed": rng.randrange(1 << 30)} if faulty else {}
    if rng.random() < OUTAGES and scenario.where != "camera":  # the feedback stops a while
        # (for a fault, after the episode that shows it: an outage would hide it)
        earliest = 1.0 if scenario.model == HEALTHY or scenario.where == "check" else 15.0
        link.update(stop_at=rng.uniform(earliest, 30.0), stop_for=rng.uniform(1.0, 4.0))
    heading = rng.uniform(0.0, 360.0)
    if scenario.model == "geodetic_as_airframe":  # psi and the motor's yaw must differ
        heading = rng.uniform(25.0, 335.0)
    attitude = (rng.uniform(*PITCH_RANGE), rng.uniform(*YAW_RANGE))
    config = SimConfig(
        uav=rng.random() < 0.5,
        ranging=rng.random() < 0.5,
        faults=FaultConfig(**link),
        behaviour=behaviour,
        heading_deg=heading,
        attitude=attitude,
    )
    return config, rng, ignored


def _bad(fields: dict[str, Any]) -> bool:
    return fields.get("verdict") in BAD and fields.get("command") != "feedback"


def _line(fields: dict[str, Any]) -> str:
    return f"{fields.get('command')} {fields.get('check')} {fields.get('verdict')}: " + str(
        fields.get("detail")
    )


def named(model: str, ignored: str, lines: list[tuple[str, str, str]]) -> bool:
    """Whether (command, verdict, sentence) lines name ``model``."""
    for command, verdict, text in lines:
        if ignored and command not in (ignored, "step"):
            continue
        if model != "lag" and verdict not in (*BAD, FAIL):
            continue
        if any(sign in text for sign in SIGNS[model]):
            return True
    return False


# -- analyze and the monitor -------------------------------------------------------------------


def monitor_verdicts(frames: list[CanFrame]) -> list[dict[str, Any]]:
    """The findings the monitor's panel counts: a live pipeline, a batch every 0.1 s of
    the bus, the source ending at the end (its last findings shown too)."""
    state = MonitorState()
    seen: list[dict[str, Any]] = []

    class Panel:
        keeps_items = True

        def handle(self, batch: Batch) -> None:
            state.fold(batch)
            seen.extend(e.fields for e in batch.events if e.topic == TOPIC_ANALYSIS_RESPONSE)

        def close(self) -> None:
            pass

    pipeline = Pipeline([Panel()], stages=Analysis().stages())
    cut = frames[0].time if frames else 0.0
    for frame in frames:
        if frame.time >= cut + 0.1:
            pipeline.deliver(frame.time)
            cut = frame.time
        pipeline.feed([frame])
    pipeline.finish(cut + 0.1)
    assert sum(state.verdicts.values()) == sum(1 for f in seen if f.get("command") != "feedback")
    return seen


def run_script(scenario: Scenario) -> Outcome:
    config, rng, ignored = config_for(scenario)
    first = first_episode(scenario.model, ignored)
    duration = rng.uniform(6.0, 40.0)  # where the run is cut
    heading = config.heading_deg or 0.0
    steps, first_done = random_script(rng, LONGEST_S, heading, config.attitude, first)
    if first is not None:  # the fault's episode is seen whole
        duration = max(duration, first_done + SEEN_FOR_S)
    steps = tuple(s for s in steps if s.at < duration)
    frames, events = run_offline(steps, duration, config, start=START)
    found = [f.fields for f in analyze(events)]
    shown = monitor_verdicts(frames)
    outcome = Outcome(scenario, about=f"{len(steps)} commands over {duration:.1f} s")
    views = {"analyze": found, "monitor": shown}
    for view, findings in views.items():
        outcome.said += [f"{view}: {_line(f)}" for f in findings if _bad(f)]
    if scenario.model == HEALTHY:
        outcome.alarms = {v: [_line(f) for f in fs if _bad(f)] for v, fs in views.items()}
    else:
        lines = [
            (str(f.get("command")), str(f.get("verdict")), str(f.get("detail"))) for f in found
        ]
        outcome.named = named(scenario.model, ignored, lines)
    return outcome


# -- the check ------------------------------------------------------------------------------


def run_check(scenario: Scenario) -> Outcome:
    config, rng, ignored = config_for(scenario)
    if rng.random() < 0.5:
        steps = STEPS
    else:
        steps = tuple(s for s in STEPS if rng.random() < 0.4) or (rng.choice(STEPS),)
    showing = SHOWN_BY.get(ignored or scenario.model, ())
    if showing and not any(s.name in showing for s in steps):  # a step that can show it
        wanted = rng.choice(showing)
        steps = tuple(s for s in STEPS if s in steps or s.name == wanted)
    # a healthy gimbal at any speed asked; a faulty one as check runs by default (a
    # drifting one turning fast for 3 s more would run into its stop, which hides it)
    speed = rng.choice((20.0, rng.uniform(5.0, 60.0)))
    options = Options(speed_dps=speed if scenario.model == HEALTHY else 20.0)
    bench = SimulatedBench(config, start=START)
    results = bench.check(steps, options)
    findings = [e.fields for e in bench.finish() if e.topic == TOPIC_ANALYSIS_RESPONSE]
    outcome = Outcome(scenario, about=", ".join(s.name for s in steps))
    failed = [r for r in results if r.verdict == FAIL]
    outcome.said = [f"step {r.step}: {r.detail}" for r in failed]
    outcome.said += [f"recording: {_line(f)}" for f in findings if _bad(f)]
    if scenario.model == HEALTHY:
        link_judged = config.faults.active
        outcome.alarms = {
            "check": [
                f"{r.step}: {r.detail}"
                for r in failed
                if not (r.step == "feedback" and link_judged)
            ],
            "recording": [_line(f) for f in findings if _bad(f)],
        }
    else:
        lines = [("step", r.verdict, r.detail) for r in results]
        lines += [
            (str(f.get("command")), str(f.get("verdict")), str(f.get("detail"))) for f in findings
        ]
        outcome.named = named(scenario.model, ignored, lines)
    return outcome


# -- the camera -----------------------------------------------------------------------------


def camera_script(rng: random.Random) -> tuple[tuple[Step, ...], float]:
    """The camera looking down at the ground, zoom commands at random moments: a zoom in
    first, then what the lens can do (no zoom out at its widest, 1x)."""
    steps = [Step(0.3, "specified_angle", {"axis": "pitch", "pitch_deg": rng.uniform(-80, -35)})]
    at = 3.0  # the turn down done: the picture's scale is then the lens's
    ratio = 1.0  # the lens's, as the simulator zooms (6x a second, at most 30x)
    for _ in range(rng.randint(1, 3)):
        ways = ["zoom_in", "zoom_in_2x"] if ratio < 10.0 else []
        ways += ["zoom_out_2x", "zoom_1x"] if ratio >= 2.0 else []
        action = rng.choice(ways)
        if action == "zoom_in":
            steps.append(Step(at, "zoom", {"action": "zoom_in"}))
            held = rng.uniform(0.4, 1.2)
            at += held
            steps.append(Step(at, "zoom", {"action": "stop"}))
            ratio = min(MAX_ZOOM, ratio + ZOOM_RATE * held)
        elif action == "zoom_1x":
            steps.append(Step(at, "zoom_1x"))
            ratio = 1.0
        else:
            steps.append(Step(at, "zoom", {"action": action}))
            ratio = ratio * 2 if action == "zoom_in_2x" else max(1.0, ratio / 2)
        at += rng.uniform(2.0, 3.0)
    return tuple(steps), at + 1.0


def run_camera(scenario: Scenario, folder: Path) -> Outcome:
    from analyzer.sim.camera.offline import record_offline

    config, rng, ignored = config_for(scenario)
    config = SimConfig(uav=True, behaviour=config.behaviour, faults=config.faults)
    steps, duration = camera_script(rng)
    path = folder / f"camera-{scenario.model}-{scenario.seed}.mcap"
    record_offline(path, steps, duration, config, streams=("main",), start=START)
    found = [f.fields for f in analyze(path)]
    path.unlink()
    outcome = Outcome(scenario, about=" ".join(s.name for s in steps))
    outcome.said = [f"analyze: {_line(f)}" for f in found if _bad(f)]
    if scenario.model == HEALTHY:
        outcome.alarms = {"camera": [_line(f) for f in found if _bad(f)]}
    else:
        lines = [
            (str(f.get("command")), str(f.get("verdict")), str(f.get("detail"))) for f in found
        ]
        outcome.named = named(scenario.model, ignored, lines)
    return outcome


def run(scenario: Scenario, folder: Path) -> Outcome:
    if scenario.where == "check":
        return run_check(scenario)
    if scenario.where == "camera":
        return run_camera(scenario, folder)
    return run_script(scenario)


def scenarios(count: int, *, first_seed: int = 0, camera: int = 0) -> Iterator[Scenario]:
    """``count`` seeds of every (model, where) pair that applies: healthy gimbals and
    every fault model but the camera's for analyze and check; the camera's
    ``camera`` seeds of healthy and zoom-ignoring gimbals."""
    for seed in range(first_seed, first_seed + count):
        for where in ("analyze", "check"):
            for model in (HEALTHY, *MODELS):
                if model != "zoom_ignored":
                    yield Scenario(seed, model, where)
    for seed in range(first_seed, first_seed + camera):
        for model in (HEALTHY, "zoom_ignored"):
            yield Scenario(seed, model, "camera")
