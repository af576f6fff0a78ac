"""A measured restoring force's coefficients in the unit of y the fit uses.

A run with a load is scaled as y = x k/N, and k = mω² moves with the frequency that
scales time: the rig's nominal one when β is measured, the small swings' ω₀ when the run
is fitted. β (1/unit²) has to follow y's unit. The record is the independent simulation
of ``test_signal_frequency`` (``solve_ivp`` half cycle by half cycle, the paper's rig)
with a cubic spring that raises the frequency by 5 % at the release.
"""

from __future__ import annotations

import functools
import warnings

import numpy as np
import pytest
from test_signal_frequency import _decay

from bayestribo.inference.preparation import prepare
from bayestribo.io.run import Run
from bayestribo.model.restoring import get_restoring, rescaled
from bayestribo.model.restoring.duffing import duffing, fit_beta

#: k₃/k [1/m²] of a frequency 5 % higher at 2 mm (Δf/f = 3/8 k₃/k A²).
K3_OVER_K = 0.05 * 8.0 / (3.0 * 2e-3**2)
RIG = {"natural_frequency_Hz": 32.6, "mass_kg": 0.035, "load_N": 0.31}


@functools.lru_cache(maxsize=1)
def _prepared():
    t, x, v = _decay(10_000.0, k3_over_k=K3_OVER_K)
    rng = np.random.default_rng(3)
    run = Run(
        t,
        x + rng.normal(0.0, 1.5e-6, t.size),
        v + rng.normal(0.0, 1.5e-7, t.size),
        {**RIG, "restoring": "duffing"},
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return prepare(run)


def test_a_rescaled_duffing_spring_is_the_same_force():
    kernel = duffing(0.3).kernel()
    ratio = 1.7
    moved = rescaled(kernel, ratio)
    assert moved.coefficients == pytest.approx((0.3 * ratio**2,), rel=1e-12)
    y = np.linspace(-2.0, 2.0, 9)
    # the same energy (in the stiffness times the new unit squared) and the same half
    # periods at the same swings
    assert np.allclose(moved.potential(y / ratio), kernel.potential(y) / ratio**2, rtol=1e-12)
    swing = np.array([0.1, 1.0, 2.0])
    assert np.allclose(
        moved.half_period_ratio(swing / ratio), kernel.half_period_ratio(swing), rtol=1e-9
    )


def test_a_force_without_coefficients_is_kept_and_a_bad_ratio_refused():
    pendulum = get_restoring("pendulum").kernel()
    assert rescaled(pendulum, 2.0) is pendulum
    assert rescaled(None, 2.0) is None
    with pytest.raises(ValueError, match="ratio"):
        rescaled(duffing(0.3).kernel(), 0.0)


def test_the_fits_beta_is_the_records_in_the_fits_unit():
    prepared = _prepared()
    decay = prepared.decay
    scale = decay.scaling.length_scale
    beta = decay.restoring.coefficients[0]
    # measured again on the decay the fit samples, in its unit: the same β
    again, se = fit_beta(decay.turning_times, decay.peaks.value / scale)
    assert beta == pytest.approx(again, abs=3.0 * se)
    # and the simulated spring's, within the turning times' interpolation (5e-3)
    assert beta == pytest.approx(K3_OVER_K * scale**2, rel=5e-3)
