"""The one sampling driver on targets with known answers (seeded).

* a correlated 3-D Gaussian: means, covariance and a marginal's distribution, with
  tolerances from the reported effective sample size;
* an AR(1) chain, whose integrated autocorrelation time (1 + ρ)/(1 − ρ) is known;
* R-hat on identical against separated chains;
* a run too short to converge is reported so, with its reason;
* a NaN log-probability is an error naming the parameters.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.stats

from bayestribo.errors import BayestriboError
from bayestribo.inference.sampling import (
    SamplerSettings,
    autocorr_time,
    rhat,
    run_ensembles,
)

MEAN = np.array([1.0, -2.0, 0.5])
SD = np.array([1.0, 0.1, 3.0])
CORR = np.array([[1.0, 0.9, -0.3], [0.9, 1.0, 0.0], [-0.3, 0.0, 1.0]])
COV = CORR * np.outer(SD, SD)
PREC = np.linalg.inv(COV)


def _gaussian(theta: np.ndarray) -> np.ndarray:
    d = np.atleast_2d(theta) - MEAN
    return -0.5 * np.einsum("ni,ij,nj->n", d, PREC, d)


@pytest.fixture(scope="module")
def gaussian_run():
    settings = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=20_000)
    rng = np.random.default_rng(0)
    start = MEAN + 0.01 * rng.standard_normal((2, 16, 3))
    return run_ensembles(_gaussian, start, settings, seed=1, names=["a", "b", "c"])


def test_a_correlated_gaussian_is_sampled_to_convergence(gaussian_run):
    run = gaussian_run
    assert run.converged, run.reasons
    flat = run.chains.reshape(-1, 3)
    ess = run.ess
    # Monte Carlo error of a mean is sd/√ESS: 5 of them is a 1-in-10⁶ miss.
    np.testing.assert_array_less(np.abs(flat.mean(axis=0) - MEAN), 5 * SD / np.sqrt(ess))
    # Variance: relative error about √(2/ESS); thinned draws are nearly independent.
    np.testing.assert_array_less(
        np.abs(flat.var(axis=0) / SD**2 - 1), 5 * np.sqrt(2 / np.minimum(ess, flat.shape[0]))
    )
    corr = np.corrcoef(flat.T)
    assert abs(corr[0, 1] - 0.9) < 0.05 and abs(corr[0, 2] + 0.3) < 0.15
    # The marginal of c is N(0.5, 3²): Kolmogorov-Smirnov on the thinned draws.
    ks = scipy.stats.kstest(flat[:, 2], "norm", args=(MEAN[2], SD[2]))
    assert ks.pvalue > 1e-4
    assert np.all(run.rhat < 1.01) and run.burn > 0 and run.thin >= 1


def test_autocorrelation_time_of_an_ar1_chain_is_the_known_one():
    # x_t = ρ x_{t-1} + √(1-ρ²) ε_t: τ = (1+ρ)/(1-ρ) exactly; the estimate's relative
    # error over 32 walkers × 20000 steps is about √(2M/(N·W)) ≈ 1-2 %.
    rng = np.random.default_rng(3)
    for rho in (0.5, 0.9):
        n, walkers = 20_000, 32
        eps = rng.standard_normal((n, walkers, 1)) * np.sqrt(1 - rho**2)
        x = np.empty_like(eps)
        x[0] = rng.standard_normal((walkers, 1))
        for t in range(1, n):
            x[t] = rho * x[t - 1] + eps[t]
        tau = autocorr_time(x)[0]
        assert tau == pytest.approx((1 + rho) / (1 - rho), rel=0.08)


def test_rhat_tells_separated_chains_from_identical_ones():
    rng = np.random.default_rng(4)
    same = rng.standard_normal((2, 2000, 1))
    assert rhat(same)[0] < 1.01
    apart = same + np.array([0.0, 1.0])[:, None, None]
    assert rhat(apart)[0] > 1.1


def test_a_run_too_short_to_converge_is_reported_with_its_reason():
    settings = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=200)
    start = MEAN + 5.0 * np.random.default_rng(5).standard_normal((2, 16, 3))
    run = run_ensembles(_gaussian, start, settings, seed=2)
    assert not run.converged
    assert any("autocorrelation times" in r or "R-hat" in r for r in run.reasons)


def test_a_nan_log_probability_is_an_error_naming_the_parameters():
    def broken(theta):
        out = _gaussian(theta)
        out[np.atleast_2d(theta)[:, 0] > 1.5] = np.nan
        return out

    settings = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=400)
    start = MEAN + 0.01 * np.random.default_rng(6).standard_normal((2, 16, 3))
    with pytest.raises(FloatingPointError, match=r"NaN at a=.*, b=.*, c="):
        run_ensembles(broken, start, settings, seed=3, names=["a", "b", "c"])


def test_bad_settings_and_start_shapes_are_refused():
    with pytest.raises(BayestriboError, match="max_steps: expected at least check_every"):
        SamplerSettings(max_steps=100)
    with pytest.raises(BayestriboError, match="n_ensembles"):
        SamplerSettings(n_ensembles=1)
    with pytest.raises(BayestriboError, match=r"initial: expected shape \(2, 16, d\)"):
        run_ensembles(_gaussian, np.zeros((16, 3)), SamplerSettings(n_walkers=16), seed=0)
