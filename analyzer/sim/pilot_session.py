"""A ground station driving like a pilot, played against the simulated gimbal: the sample
``samples/pilot-candump.log`` (a stick, a re-sent target, a tracker), made deterministically.
"""

from __future__ import annotations

from analyzer.protocol.types import CanFrame
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.engine import SimConfig
from analyzer.sim.ground import Step
from analyzer.sim.offline import run_offline
from analyzer.sim.pilot import Stick

START = 1715684400.0  # 2024-05-14 11:00:00 UTC, an hour after the flight sample
SECONDS = 36.0
CHANNEL = "can0"
BOX = {"x": 4400, "y": 3900, "width": 480, "height": 320}  # the target, right of centre
# The gimbal obeys, 0.3 s late.
BEHAVIOUR = Behaviour(lag_s=0.3)


def pilot_steps() -> tuple[Step, ...]:
    """Three stick movements (zeros for 1 s after each, then nothing), specified_angle
    pitch -45 re-sent every 0.2 s for 3 s, a tracker moving its box at 10 Hz for 6 s."""
    steps: list[Step] = []
    for n, (at, length, pan, tilt) in enumerate(
        ((2.0, 2.5, 20.0, 0.0), (8.0, 2.0, 0.0, -15.0), (13.0, 3.0, -12.0, 8.0))
    ):
        stick = Stick(pan, tilt, centred_s=1.0, seed=n)
        steps.append(Step(at, "gimbal_control", {}, until=at + length, stick=stick))
    steps += [Step(20.0 + 0.2 * i, "specified_angle", {"pitch_deg": -45}) for i in range(16)]
    steps.append(Step(26.0, "tracking", BOX))
    for i in range(1, 60):  # the gimbal has centred it: the box stays near the centre
        box = dict(BOX, x=4096 + 6 * (i % 5 - 2), y=4096 + 4 * (i % 3 - 1))
        steps.append(Step(26.0 + 0.1 * i, "tracking", box))
    steps.append(Step(32.5, "tracking_stop"))
    return tuple(steps)


def pilot_frames() -> list[CanFrame]:
    """The bus: the ground station's commands and the simulated gimbal's feedback."""
    frames, _ = run_offline(
        pilot_steps(), SECONDS, SimConfig(behaviour=BEHAVIOUR), start=START, channel=CHANNEL
    )
    return frames


def pilot_log() -> bytes:
    """The bus as ``candump -L`` writes it."""
    lines = [
        f"({f.time:.6f}) {f.channel} {f.can_id:08X}#{f.data.hex().upper()}\n"
        for f in pilot_frames()
    ]
    return "".join(lines).encode()
