"""What a misfit is decides the advice's order: a smooth departure along the decay is
the law's (another law first), a misfit about the stop is the stop's (a wider μ_s/μ_k
prior first); a half period that shortens as the swing decays by what a drag of the
record's damping makes is the drag's (another law before another spring)."""

from __future__ import annotations

import math

import numpy as np

from bayestribo.inference.checks import Misfit, drag_change, misfit_of_the_law
from bayestribo.inference.likelihood import ShapeDeparture
from bayestribo.signal.frequency import FrequencyTrend


def _shape(chi2: float, p: float) -> ShapeDeparture:
    return ShapeDeparture(chi2, 4, p, 0.01, 0.001, 0, np.zeros(3))


def test_a_misfit_mostly_along_the_decay_is_the_laws_and_one_about_the_stop_is_not() -> None:
    # a drag's record on the default law (benchmarks/README.md: 97 % of the χ²)
    assert misfit_of_the_law(Misfit(108_119.0, 32, 0.0), _shape(104_636.7, 0.0))
    # a stop beyond μ_s/μ_k's bound: a significant smooth part, a small share
    assert not misfit_of_the_law(Misfit(4162.0, 20, 0.0), _shape(21.7, 2.3e-4))
    # no smooth departure, or no misfit at all
    assert not misfit_of_the_law(Misfit(1536.0, 40, 1e-56), _shape(5.0, 0.3))
    assert not misfit_of_the_law(Misfit(30.0, 32, 0.6), _shape(2.0, 0.7))
    assert not misfit_of_the_law(Misfit(900.0, 20, 0.0), _shape(math.nan, math.nan))


def _trend(change: float) -> FrequencyTrend:
    return FrequencyTrend(change, -50.0 if change < 0 else 50.0, 40)


def test_a_drags_change_is_second_order_in_the_damping_and_shortens_the_half_period() -> None:
    # turning points of a decay at ζ_e = 0.014 over its first swings (the drag's)
    zeta = 0.014
    turning = 1e-3 * np.exp(-math.pi * zeta * np.arange(10)) * (-1.0) ** np.arange(10)
    assert drag_change(_trend(-2.4e-4), turning)  # the quadratic drag's, measured
    assert not drag_change(_trend(+2.4e-4), turning)  # a spring that stiffens
    assert not drag_change(_trend(-5e-4), turning)  # beyond 2 ζ_e²: a softening spring
    assert not drag_change(None, turning)
    assert not drag_change(_trend(-2.4e-4), turning[:1])
