"""`check` on a link that loses feedback: a step the feedback did not allow to be judged
is run again, a lost message that changes nothing fails nothing, a gimbal that does not
obey is not run again. On the simulated bench in virtual time (``analyzer.check.offline``).
"""

from __future__ import annotations

import pytest

from analyzer.check.offline import START, SimulatedBench
from analyzer.check.runner import MAX_TRIES
from analyzer.check.steps import STEPS, Options, select
from analyzer.protocol.check_fields import FAIL, PASS, SKIPPED
from analyzer.sim.behaviour import Behaviour
from analyzer.sim.engine import SimConfig
from analyzer.sim.faults import FaultConfig


def test_a_step_a_silence_cut_is_run_again_and_passes() -> None:
    # pitch_angle's move starts 1.5 s in (after its start, 0 to 45): silent from 1.9 to 4.9 s
    bench = SimulatedBench(SimConfig(faults=FaultConfig(stop_at=1.9, stop_for=3.0)))
    (result,) = bench.check(select("pitch_angle"))
    assert result.verdict == PASS
    assert result.figures["tries"] == 2
    assert result.figures["slew_dps"] == pytest.approx(60.0, rel=0.05)
    assert "; on try 2 of 3: the feedback did not allow a judgement before (no feedback for" in (
        result.detail
    )


def test_feedback_gone_for_good_fails_as_no_feedback_after_three_tries() -> None:
    bench = SimulatedBench(SimConfig(faults=FaultConfig(stop_at=1.9, stop_for=600.0)))
    (result,) = bench.check(select("pitch_angle"))
    assert result.verdict == FAIL and result.figures["tries"] == MAX_TRIES
    assert result.detail.startswith("no feedback")


def test_a_lost_message_that_changes_nothing_fails_nothing() -> None:
    """The demo's faults (a segment in 50 dropped, damaged, repeated or late): every
    step of a healthy gimbal passes, the feedback step (which judges the link) aside."""
    faults = FaultConfig(drop=0.02, corrupt=0.02, duplicate=0.02, delay=0.02, seed=11)
    results = SimulatedBench(SimConfig(faults=faults, heading_deg=75.0)).check(STEPS)
    for result in results:
        if result.step != "feedback":
            assert result.verdict in (PASS, SKIPPED), (result.step, result.detail)


def test_a_gimbal_that_does_not_obey_is_not_run_again() -> None:
    """A sluggish gimbal on a lossy link: its failure is decided, not for want of
    feedback, so it is said once."""
    faults = FaultConfig(drop=0.05, seed=3)
    sluggish = SimConfig(behaviour=Behaviour(speed=0.3), faults=faults)
    results = SimulatedBench(sluggish).check(select("pitch_angle,pan_speed"), Options())
    for result in results:
        assert result.verdict == FAIL and "tries" not in result.figures, result.detail


def test_a_late_gimbal_passes_and_is_said_to_be_late() -> None:
    """Latency is no pass limit of the check, but it is said: the moves start late, the
    speed steps follow late (their rate is the analysis', late motion included)."""
    bench = SimulatedBench(SimConfig(behaviour=Behaviour(lag_s=0.6)), start=START)
    results = {r.step: r for r in bench.check(select("pitch_angle,pan_speed"))}
    assert results["pitch_angle"].verdict == PASS
    assert "it began to move about 0.6 s late" in results["pitch_angle"].detail
    pan = results["pan_speed"]
    assert pan.verdict == PASS and "it followed about 0.6 s late" in pan.detail
    assert pan.figures["rate_dps"] == pytest.approx(20.0, rel=0.1)
