"""The one sampling driver on targets with known answers (seeded).

* a correlated 3-D Gaussian: means, covariance and a marginal's distribution, with
  tolerances from the reported effective sample size;
* an AR(1) chain, whose integrated autocorrelation time (1 + ρ)/(1 − ρ), hence its
  effective sample size, is known;
* R-hat on identical against separated chains;
* a run too short to converge is reported so, with its reason;
* a NaN log-probability is an error naming the parameters.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
import scipy.stats

from bayestribo.errors import BayestriboError
from bayestribo.inference.sampling import (
    NaNLogProbabilityError,
    SamplerSettings,
    autocorr_time,
    effective_sample_size,
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
    # The stopping rule: at least 50 autocorrelation times after burn.
    assert run.n_steps - run.burn >= 50 * np.max(run.autocorr_time)


def test_the_run_summary_names_each_parameter(gaussian_run):
    summary = gaussian_run.summary(0.9)
    assert list(summary) == ["a", "b", "c"]
    c = summary["c"]
    assert c.prob == 0.9 and c.kind == "posterior"
    # The 90 % interval of N(0.5, 3²) is 0.5 ± 1.645·3; its ends are known to about
    # 2.1·sd/√ESS each (the sd of a 5 % quantile estimate, in units of the sd).
    half = scipy.stats.norm.ppf(0.95) * SD[2]
    err = 5 * 2.1 * SD[2] / np.sqrt(gaussian_run.ess[2])
    assert abs(c.low - (MEAN[2] - half)) < err and abs(c.high - (MEAN[2] + half)) < err
    with pytest.raises(BayestriboError, match="prob"):
        gaussian_run.summary(1.5)


def test_autocorrelation_time_and_ess_of_an_ar1_chain_are_the_known_ones():
    # x_t = ρ x_{t-1} + √(1-ρ²) ε_t: τ = (1+ρ)/(1-ρ) exactly, so ESS = N·W/τ; the
    # estimate's relative error over 32 walkers × 20000 steps is about √(2M/(N·W)),
    # 1-2 %, with M the window (about 5τ).
    rng = np.random.default_rng(3)
    for rho in (0.5, 0.9):
        n, walkers = 20_000, 32
        eps = rng.standard_normal((n, walkers, 1)) * np.sqrt(1 - rho**2)
        x = np.empty_like(eps)
        x[0] = rng.standard_normal((walkers, 1))
        for t in range(1, n):
            x[t] = rho * x[t - 1] + eps[t]
        tau = autocorr_time(x)[0]
        exact = (1 + rho) / (1 - rho)
        assert tau == pytest.approx(exact, rel=0.08)
        assert effective_sample_size(x)[0] == pytest.approx(n * walkers / exact, rel=0.08)
    with pytest.raises(BayestriboError, match=r"chain: expected shape \(steps, walkers"):
        effective_sample_size(np.zeros((100, 4)))


def test_rhat_tells_separated_chains_from_identical_ones():
    rng = np.random.default_rng(4)
    same = rng.standard_normal((2, 2000, 1))
    assert rhat(same)[0] < 1.01
    apart = same + np.array([0.0, 1.0])[:, None, None]
    assert rhat(apart)[0] > 1.1


def test_a_run_too_short_to_converge_is_reported_with_its_reason():
    # 200 steps cannot hold a burn plus 50 autocorrelation times (τ is over 4 steps
    # even for a well-mixed 3-D Gaussian).
    settings = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=200)
    start = MEAN + 5.0 * np.random.default_rng(5).standard_normal((2, 16, 3))
    run = run_ensembles(_gaussian, start, settings, seed=2)
    assert not run.converged
    assert any("autocorrelation times" in r for r in run.reasons), run.reasons
    assert run.names == ("theta[0]", "theta[1]", "theta[2]")


def test_ensembles_stuck_in_separate_modes_are_not_converged():
    # Two far-apart narrow modes; each ensemble starts in its own and never crosses:
    # each chain looks fine alone, only R-hat between the ensembles sees the problem.
    def two_modes(theta):
        d = np.atleast_2d(theta)
        a = -0.5 * np.sum((d - 5.0) ** 2, axis=1) / 0.01
        b = -0.5 * np.sum((d + 5.0) ** 2, axis=1) / 0.01
        return np.logaddexp(a, b)

    settings = SamplerSettings(n_walkers=8, n_ensembles=2, max_steps=600)
    rng = np.random.default_rng(7)
    start = 0.05 * rng.standard_normal((2, 8, 2)) + np.array([5.0, -5.0])[:, None, None]
    run = run_ensembles(two_modes, start, settings, seed=8, names=["x", "y"])
    assert not run.converged
    assert any(re.fullmatch(r"R-hat \d+\.\d+ >= 1\.01 for [xy]", r) for r in run.reasons), (
        run.reasons
    )
    assert np.all(run.rhat > 1.1)


def test_a_nan_log_probability_is_an_error_naming_the_parameters():
    def broken(theta):
        out = _gaussian(theta)
        out[np.atleast_2d(theta)[:, 0] > 1.5] = np.nan
        return out

    settings = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=400)
    start = MEAN + 0.01 * np.random.default_rng(6).standard_normal((2, 16, 3))
    with pytest.raises(NaNLogProbabilityError, match=r"NaN at a=.*, b=.*, c=") as info:
        run_ensembles(broken, start, settings, seed=3, names=["a", "b", "c"])
    # A package error, and a FloatingPointError like the posterior's own NaN error.
    assert isinstance(info.value, BayestriboError)
    assert isinstance(info.value, FloatingPointError)
    row = [float(v) for v in re.search(r"a=(\S+), b=(\S+), c=(\S+)$", str(info.value)).groups()]
    assert row[0] > 1.5 and np.isnan(broken(np.array([row]))[0])


def test_bad_settings_and_start_shapes_are_refused():
    with pytest.raises(BayestriboError, match="max_steps: expected at least check_every"):
        SamplerSettings(max_steps=100)
    with pytest.raises(BayestriboError, match="n_ensembles"):
        SamplerSettings(n_ensembles=1)
    with pytest.raises(BayestriboError, match=r"initial: expected shape \(2, 16, d\)"):
        run_ensembles(_gaussian, np.zeros((16, 3)), SamplerSettings(n_walkers=16), seed=0)
