"""The frequency nuisance the check stage carries into the intervals
(:func:`bayestribo.inference.checks.frequency_nuisance_sd`), on turning times with a
known change of the half period and timing noise of 1/|Y| (a velocity's zero crossing
timed by the noise over its slope)."""

from __future__ import annotations

import numpy as np

from bayestribo.inference.checks import frequency_nuisance_sd
from bayestribo.signal.frequency import turning_point_trend

HALF_PERIOD, RATIO, SEEDS = 7.5, 0.78, 400  # [s], |Y| ratio a half cycle, noise draws


def _trends(change: float, timing: float) -> list:
    """Turning-point trends of ``SEEDS`` noise draws: 20 turning points decaying by
    ``RATIO`` a half cycle, the half period changing by ``change`` from the largest swing
    to the smallest (the trend model's own form), each time off by N(0, ``timing``)
    [s] at the largest swing and by that over |Y_n|/|Y_0| at the others."""
    y = 0.3 * (-RATIO) ** np.arange(20)
    swing = 0.5 * np.abs(np.diff(y))
    slope = -change * HALF_PERIOD / (swing.max() - swing.min())
    times = np.concatenate(([0.0], np.cumsum(HALF_PERIOD + slope * (swing - swing.mean()))))
    rng = np.random.default_rng(11)
    scale = timing * abs(y[0]) / np.abs(y)
    return [turning_point_trend(times + scale * rng.normal(size=y.size), y) for _ in range(SEEDS)]


def _noise(trends: list) -> np.ndarray:
    """Each trend's standard error of the change [-]."""
    return np.array([abs(t.change / t.z) for t in trends])


def test_a_linear_oscillators_trend_within_its_noise_carries_no_nuisance():
    trends = _trends(0.0, 2e-3)
    eps = np.array([frequency_nuisance_sd(t) for t in trends])
    within = np.array([abs(t.z) <= 1.0 for t in trends])
    assert within.sum() > SEEDS // 2  # the test has cases of both kinds
    assert np.all(eps[within] == 0.0)
    # On average the nuisance's span (2ε)² stays below the trend's noise σ_Δ²: a change
    # that is noise is not counted as a change (½√(Δ̂² + σ_Δ²) made it 2 σ_Δ²).
    assert np.mean((2.0 * eps) ** 2) < np.mean(_noise(trends) ** 2)


def test_the_nuisance_measures_the_square_of_a_change_without_its_noise():
    change = 2e-3
    trends = _trends(change, 2e-3)
    sd = _noise(trends)
    # σ_Δ about half the change: counting the noise twice would add 2 σ_Δ² ≈ ½ Δ²
    assert 0.3 * change < np.median(sd) < 0.7 * change
    span2 = np.array([(2.0 * frequency_nuisance_sd(t)) ** 2 for t in trends])
    # (2ε)² = max(Δ̂² - σ_Δ², 0) has the mean Δ² (less the few draws cut at 0); its
    # standard error over the draws
    se = span2.std(ddof=1) / np.sqrt(SEEDS)
    assert abs(span2.mean() - change**2) < 3.0 * se
    assert 2.0 * np.mean(sd**2) > 6.0 * se  # the old mean is far outside that


def test_a_clear_trend_carries_half_its_change():
    # a Duffing spring's change at tens of standard errors: ½|Δ̂| to within 1/z² of it
    for trend in _trends(2e-3, 1e-4)[:20]:
        assert abs(trend.z) > 10
        half = 0.5 * abs(trend.change)
        assert half * (1.0 - 1.0 / trend.z**2) <= frequency_nuisance_sd(trend) <= half


def test_no_trend_no_nuisance():
    assert frequency_nuisance_sd(None) == 0.0
