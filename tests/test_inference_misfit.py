"""The misfit test holds the uncertainty of a noise measured at rest (no false alarms
from a short rest), and keeps its power where the noise is well measured."""

from __future__ import annotations

import numpy as np
import scipy.stats

from bayestribo.inference.pipeline import misfit_p_value
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.noise import noise_model
from bayestribo.synthetic import Release, Sensor
from bayestribo.synthetic.recording import simulate


def _p_values(n_rest: int, m: int, dof: float | None, runs: int, seed: int) -> np.ndarray:
    """p-values of residuals that follow the law exactly, standardised by a variance
    measured from ``n_rest`` samples of rest (one segment)."""
    rng = np.random.default_rng(seed)
    rest = rng.normal(size=(runs, n_rest))
    measured = np.var(rest, axis=1, ddof=1)  # the true variance is 1
    chi2 = rng.chisquare(m, size=runs) / measured
    return np.array([misfit_p_value(c, m, dof) for c in chi2])


def test_a_short_rest_gives_uniform_p_values_with_its_degrees_of_freedom():
    p = _p_values(n_rest=200, m=2000, dof=199, runs=2000, seed=1)
    assert scipy.stats.kstest(p, "uniform").pvalue > 1e-3
    assert np.mean(p < 1e-3) < 3e-3  # false alarms at their nominal rate
    # the χ² test that takes the measured variance as exact raises false alarms
    exact = _p_values(n_rest=200, m=2000, dof=None, runs=2000, seed=1)
    assert np.mean(exact < 1e-3) > 0.1


def test_a_real_misfit_is_still_found_with_a_long_rest():
    rng = np.random.default_rng(2)
    measured = np.var(rng.normal(size=20_000), ddof=1)
    chi2 = 1.3 * rng.chisquare(2000) / measured  # residuals 14 % larger than the noise
    assert misfit_p_value(chi2, 2000, 19_999) < 1e-6


def test_the_noise_model_states_the_degrees_of_freedom_of_its_rest():
    run = simulate(
        release=Release(initial_displacement_m=1e-3),
        sensor=Sensor(
            sample_rate_Hz=3000.0, displacement_noise_m=1.5e-6, velocity_noise_m_per_s=1.5e-7
        ),
        seed=21,
    )
    decay = energy_decay(run.time, run.displacement, run.velocity, rig=run.rig())
    noise = noise_model(decay, run.metadata)
    assert noise.exceeds_nominal
    segments = decay.noise.source.count(" and ") + 1
    assert noise.measured_dof == decay.noise.n_samples - segments
    nominal = noise_model(
        decay, {"displacement_resolution_m": 1.0, "velocity_resolution_m_per_s": 1.0}
    )
    assert nominal.measured_dof is None  # the resolution is used: taken as exact
