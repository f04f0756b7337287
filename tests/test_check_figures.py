"""The bench check's figures, measured from feedback samples as the check receives them."""

from __future__ import annotations

import pytest

from analyzer.analysis.samples import MOTOR_YAW, PITCH, YAW, Sample
from analyzer.check.figures import feedback_figures, longest_silence, move_figures, rate_figure


def pitch_move(
    start: float, target: float, dps: float, lag: float, period: float = 0.5, until: float = 4.0
) -> list[Sample]:
    """Samples every ``period`` of a pitch move that starts ``lag`` s after the command (t=0)."""
    samples = []
    t = 0.2
    while t <= until:
        moved = max(0.0, t - lag) * dps
        value = max(target, start - moved) if target < start else min(target, start + moved)
        samples.append(Sample(t, value, 0.0, 0.0, False, 1))
        t += period
    return samples


def test_slew_comes_from_the_moving_part_not_from_the_end_points() -> None:
    before = Sample(-0.3, 0.0, 0.0, 0.0, False, 1)
    samples = pitch_move(0.0, -90.0, 60.0, lag=0.4)
    figures = move_figures(PITCH, -90.0, 0.0, before, samples, 1.0)
    # End points would say 90 deg over (1.7 - 0.2) s = 60, or less with the lag; the fit
    # of the samples in motion gives the true speed and the lag back.
    assert figures.slew_dps == pytest.approx(60.0)
    assert figures.latency_s == pytest.approx(0.4)
    assert figures.error_deg == pytest.approx(0.0) and figures.overshoot_deg == 0.0
    assert figures.settle_s == pytest.approx(2.2)  # the first sample at -90 (0.4 + 1.5 s)


def test_a_move_that_falls_short_reports_its_error() -> None:
    before = Sample(-0.3, 0.0, 0.0, 0.0, False, 1)
    samples = pitch_move(0.0, -63.0, 60.0, lag=0.0)
    figures = move_figures(PITCH, -90.0, 0.0, before, samples, 1.0)
    assert figures.error_deg == pytest.approx(-27.0)
    assert figures.slew_dps == pytest.approx(60.0)


def test_overshoot_is_measured_past_the_target_on_the_way_it_moved() -> None:
    values = [0.0, -30.0, -60.0, -95.0, -92.0, -90.0, -90.0]
    samples = [Sample(0.5 * i, v, 0.0, 0.0, False, 1) for i, v in enumerate(values)]
    figures = move_figures(PITCH, -90.0, -0.1, None, samples, 1.0)
    assert figures.overshoot_deg == pytest.approx(5.0)


def test_yaw_from_north_is_measured_across_north() -> None:
    # 350 -> 20 through north: 30 deg at 20 deg/s, not 330 deg the other way.
    values = [350.0, 350.0, 0.0, 10.0, 20.0, 20.0, 20.0]
    samples = [Sample(0.5 * i, 0.0, v, 0.0, False, 1) for i, v in enumerate(values)]
    figures = move_figures(YAW, 20.0, 0.6, samples[0], samples[1:], 1.0)
    assert figures.slew_dps == pytest.approx(20.0)
    assert figures.error_deg == pytest.approx(0.0)


def test_rate_of_a_speed_command_starts_where_the_gimbal_moved() -> None:
    # Still for the first sample, then -20 deg/s on the yaw motor.
    samples = [
        Sample(0.5 * i, 0.0, 0.0, -20.0 * max(0.0, 0.5 * i - 0.5), False, 1) for i in range(7)
    ]
    assert rate_figure(MOTOR_YAW, samples, 1.0) == pytest.approx(-20.0)
    assert rate_figure(MOTOR_YAW, samples[:1], 1.0) is None


def test_feedback_figures_count_the_messages_missing_from_the_rhythm() -> None:
    times = [10.0, 10.5, 11.0, 12.5, 13.0]  # two missing between 11.0 and 12.5
    figures = feedback_figures(times, 1, 10.0, 13.2, 0.5)
    assert figures.messages == 5 and figures.lost == 2 and figures.crc_errors == 1
    assert figures.period_s == pytest.approx(0.5)
    assert longest_silence(times, 10.0, 13.2) == (pytest.approx(1.5), 11.0)
    late_together = feedback_figures([10.0, 10.5, 11.5, 11.5, 12.0], 0, 10.0, 12.2, 0.5)
    assert late_together.lost == 0  # two read at once after a stall: none missing
    silent = feedback_figures([], 0, 0.0, 2.0, 0.5)
    assert silent.messages == 0 and silent.lost == 4 and silent.period_s is None
