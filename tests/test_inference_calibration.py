"""A small seeded calibration check of the fit: catches gross miscalibration.

Six runs are simulated with parameters drawn from a box inside the default priors
(ζ, μ_k uniform on [0.015, 0.04], μ_s/μ_k uniform on [1, 3], 2 kHz, an ideal release,
white noise at 1x and 30x the vibrometer resolution) and fitted with the default
priors. For each fit the squared Mahalanobis distance of the truth (ζ, μ_k) from the
posterior mean, in the posterior covariance, is χ²(2) when the posterior is
calibrated and Gaussian (ζ and μ_k are strongly correlated, so the two coordinates
are not tested separately); the sum over the six fits is χ²(12). The test accepts
the central 99.8 % of that distribution, [2.2, 32.9]: posterior standard deviations
too small by a factor of two (expected sum 48) or too large by a factor of three
(expected sum 1.3) fail with high probability.
The full simulation-based calibration (hundreds of replications, rank histograms) is
``benchmarks/sbc.py``.
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy import stats

from bayestribo.inference import fit
from bayestribo.synthetic import (
    DISPLACEMENT_RESOLUTION_M,
    VELOCITY_RESOLUTION_M_PER_S,
    DissipationLaw,
    Release,
    Sensor,
    simulate,
)

N_RUNS = 6


def _distance(level: float, seed: int) -> tuple[float, bool]:
    rng = np.random.default_rng(seed)
    zeta, mu_k = rng.uniform(0.015, 0.04, 2)
    ratio = rng.uniform(1.0, 3.0)
    run = simulate(
        DissipationLaw(zeta=zeta, mu_k=mu_k, mu_s=mu_k * ratio),
        release=Release(magnet_fade_s=0.0),
        sensor=Sensor(
            sample_rate_Hz=2000.0,
            displacement_noise_m=level * DISPLACEMENT_RESOLUTION_M,
            velocity_noise_m_per_s=level * VELOCITY_RESOLUTION_M_PER_S,
        ),
        seed=seed,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = fit(run, seed=seed)
    draws = np.column_stack([result.samples("zeta"), result.samples("mu_k")])
    err = draws.mean(axis=0) - np.array([zeta, mu_k])
    cov = np.cov(draws, rowvar=False)
    return float(err @ np.linalg.solve(cov, err)), result.converged


def test_truth_distances_follow_chi2() -> None:
    out = [_distance(level, 100 + i) for i, level in enumerate([1.0, 30.0] * (N_RUNS // 2))]
    distances = np.array([d for d, _ in out])
    assert all(c for _, c in out), "every fit of a clean simulated run converges"
    total = float(distances.sum())
    lo, hi = stats.chi2.ppf([0.001, 0.999], 2 * N_RUNS)
    print(f"chi2(12) sum {total:.2f}, per fit {distances.round(2).tolist()}")
    assert lo < total < hi, (total, distances.round(2).tolist())
