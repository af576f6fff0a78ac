"""The likelihood: marginalised equilibrium error, models, discrepancy term."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from _sim import simulate_flat
from scipy.special import logsumexp
from scipy.stats import chi2 as chi2_dist
from scipy.stats import kstest, multivariate_normal

from bayestribo.inference.likelihood import SHAPE_TERMS, PiLikelihood
from bayestribo.inference.posterior import Posterior
from bayestribo.inference.priors import default_priors
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.increments import pi_data
from bayestribo.signal.noise import noise_model

TRUE = {"zeta": 0.0236, "mu_k": 0.0294}


@pytest.fixture(scope="module")
def setup():
    run = simulate_flat(
        seed=12,
        displacement_noise_m=1.5e-6,
        velocity_noise_m_per_s=1.5e-7,
        sample_rate_Hz=5000.0,
        offset_m=2e-4,
        **TRUE,
    )
    decay = energy_decay(run.time, run.displacement, run.velocity, rig=run.rig())
    data = pi_data(decay, noise_model(decay, run.metadata), grid_points=40)
    return run, decay, data


def _col(v):
    return np.array([[v]])


def _params(zeta, mu_k, mu_s, y0):
    """The likelihood's parameter mapping from ζ, μ_k, μ_s and y0 (each (1, 1))."""
    mu_k, mu_s = np.asarray(mu_k, dtype=float), np.asarray(mu_s, dtype=float)
    ratio = np.divide(mu_s, mu_k, out=np.ones_like(mu_k), where=mu_k > 0)
    return {"zeta": zeta, "mu_k": mu_k, "mu_s_ratio": ratio, "y0": y0}


def test_marginal_equals_numerical_integral_over_the_offset(setup):
    """Analytic marginalisation of (δ₀, δ₁) and the noise level's error against a
    brute-force 3-D quadrature (a Gaussian sampled at 0.27 widths: the trapezoid rule
    is then exact to far below the tolerance)."""
    _, _, data = setup
    lik = PiLikelihood(data, offset_sd=2e-3, drift_sd=2e-5)
    args = _params(_col(0.02361), _col(0.02938), _col(0.0353), _col(data.y0))
    analytic = lik.log_likelihood(args)[0]
    model = lik.model_increments(args)[0]
    x = data.offset_design
    assert x.shape == (data.increments.size, 3)
    assert np.all(x[:, 2] > 0)  # the noise bias's standard error, in every increment
    w = 1.0 / data.variance
    prior_sd = np.array([2e-3, 2e-5, 1.0])
    prec = x.T @ (w[:, None] * x) + np.diag(prior_sd**-2)
    centre = np.linalg.solve(prec, x.T @ (w * (data.increments - model)))
    width = np.sqrt(np.diag(np.linalg.inv(prec)))
    grids = [c + np.linspace(-8, 8, 61) * s for c, s in zip(centre, width, strict=True)]
    d = np.stack(np.meshgrid(*grids, indexing="ij"), axis=-1)  # (61, 61, 61, 3)
    resid = data.increments - d @ x.T - model
    cond = -0.5 * np.sum(resid**2 * w + np.log(2 * np.pi * data.variance), axis=-1)
    norm = np.sum(np.log(np.sqrt(2 * np.pi) * prior_sd))
    prior = -0.5 * np.sum((d / prior_sd) ** 2, axis=-1) - norm
    cell = np.prod([g[1] - g[0] for g in grids])
    numeric = logsumexp(cond + prior) + np.log(cell)
    assert analytic == pytest.approx(numeric, abs=1e-6)
    # the conditional mean of (δ₀, δ₁) is the quadrature's
    weights = np.exp(cond + prior - logsumexp(cond + prior))
    mean = np.tensordot(weights, d, axes=3)
    assert lik.offset(args)[0] == pytest.approx(mean[:2], rel=1e-6)


def test_equilibrium_error_is_recovered(setup):
    """The conditional δ₀ matches the error of the equilibrium estimate."""
    run, decay, data = setup
    lik = PiLikelihood(data)
    sim = run.metadata["simulation"]
    delta = lik.offset(
        _params(_col(sim["zeta"]), _col(sim["mu_k"]), _col(sim["mu_s"]), _col(data.y0))
    )
    error = (decay.equilibrium - sim["offset_m"]) / decay.scaling.length_scale
    # δ₀ is the offset at τ = 0 of the error, in units of y; the estimate's own
    # uncertainty is about σ_y/√(samples) ≈ 1e-4 here.
    assert delta[0, 0] == pytest.approx(-error, abs=5e-4)


def test_averaged_model_bias_shows_at_vibrometer_precision(setup):
    """At the truth the exact model fits; the averaged one is many σ off (bias ~2ζ²)."""
    run, _, data = setup
    sim = run.metadata["simulation"]
    lik_exact = PiLikelihood(data, model="exact")
    lik_avg = PiLikelihood(data, model="averaged")
    args = _params(_col(sim["zeta"]), _col(sim["mu_k"]), _col(sim["mu_s"]), _col(data.y0))
    r_exact = lik_exact.standardized_residuals(args)
    r_avg = lik_avg.standardized_residuals(args)
    # y0 is the noisy observed value (off by ~σ_y): allow a loose χ² for the exact one.
    assert np.sum(r_exact**2) < 20 * data.increments.size
    assert np.sum(r_avg**2) > 20 * np.sum(r_exact**2)


def test_discrepancy_term_inflates_variance_independently_of_grid(setup):
    run, decay, _ = setup
    noise = noise_model(decay, run.metadata)
    coarse = pi_data(decay, noise, grid_points=20)
    fine = pi_data(decay, noise, grid_points=80)
    # ∫E² over the record, the discrepancy's variance scale, is additive.
    assert coarse.energy_squared.sum() == pytest.approx(fine.energy_squared.sum(), rel=1e-3)
    assert coarse.variance[:-1].sum() == pytest.approx(fine.variance[:-1].sum(), rel=0.05)
    lik = PiLikelihood(coarse)
    assert np.all(lik.variance(np.array([[1e-3]])) > coarse.variance)


def test_posterior_skips_impossible_priors_and_refuses_nan(setup):
    _, _, data = setup
    post = Posterior(default_priors(data.y0), PiLikelihood(data))
    rows = np.array([[0.0236, 0.0294, 1.2, data.y0], [-0.1, 0.0294, 1.2, data.y0]])
    lp = post(rows)
    assert np.isfinite(lp[0]) and lp[1] == -np.inf
    assert post(np.array([[0.0236, np.nan, 1.2, data.y0]]))[0] == -np.inf  # outside prior

    class NaNLikelihood(PiLikelihood):
        def log_likelihood(self, *args, **kwargs):
            return np.full(np.size(args[0]["y0"]), np.nan)

    broken = Posterior(default_priors(data.y0), NaNLikelihood(data))
    with pytest.raises(FloatingPointError, match=r"zeta=0\.0236"):
        broken(rows[:1])


def test_shape_discrepancy_marginal_is_the_gaussian_with_its_covariance(setup):
    """Marginalising the equilibrium and shape coefficients analytically equals the
    multivariate normal of the residuals with covariance diag(V + s²∫E²) + X P Xᵀ."""
    _, _, data = setup
    lik = PiLikelihood(data, offset_sd=2e-3, drift_sd=2e-5)
    args = _params(_col(0.02361), _col(0.02938), _col(0.0353), _col(data.y0))
    resid = data.increments - lik.model_increments(args)[0]
    for s, sc in [(None, 1e-3), (1e-4, 1e-2), (3e-3, 1e-5)]:
        disc = None if s is None else _col(s)
        analytic = lik.log_likelihood(args, disc, _col(sc))[0]
        var = data.variance + (0.0 if s is None else s * s * data.energy_squared)
        # the shape columns D_j P_k(u_j), built here from the definition
        mid = 0.5 * (data.tau_grid[:-1] + data.tau_grid[1:])
        u = 2 * (mid - mid[0]) / (mid[-1] - mid[0]) - 1
        legendre = np.stack(
            [np.polynomial.legendre.Legendre.basis(k)(u) for k in range(SHAPE_TERMS)], axis=1
        )
        x = np.hstack([data.offset_design, data.increments[:, None] * legendre])
        prior = np.diag([2e-3**2, 2e-5**2, 1.0] + [sc**2] * SHAPE_TERMS)
        cov = np.diag(var) + x @ prior @ x.T
        direct = multivariate_normal(np.zeros(resid.size), cov).logpdf(resid)
        assert analytic == pytest.approx(direct, abs=1e-6 * max(1.0, abs(direct)))


def test_shape_departure_is_chi2_under_the_law_and_finds_an_injected_departure(setup):
    """Increments drawn from the law with the stated variances give the test's χ² its
    χ²(K) distribution; a smooth relative departure added to them is found, with its
    size at the increment where it is largest."""
    _, _, data = setup
    lik = PiLikelihood(data)
    truth = {"zeta": 0.02361, "mu_k": 0.02938, "mu_s_ratio": 0.0353 / 0.02938, "y0": data.y0}
    model = lik.model_increments({k: _col(v) for k, v in truth.items()})[0]
    rng = np.random.default_rng(3)
    chi2 = []
    for _ in range(300):
        noisy = model + rng.normal(0.0, np.sqrt(data.variance))
        other = PiLikelihood(dataclasses.replace(data, increments=noisy))
        chi2.append(other.shape_departure(truth).chi2)
    assert kstest(chi2, chi2_dist(SHAPE_TERMS).cdf).pvalue > 0.01
    # a departure of +0.5 % at the start to -0.5 % at the end, curving in between
    u = 2 * np.arange(model.size) / (model.size - 1) - 1
    g = 5e-3 * np.polynomial.legendre.Legendre([0.0, -0.6, 0.0, -0.4])(u)
    noisy = model * (1 + g) + rng.normal(0.0, np.sqrt(data.variance))
    found = PiLikelihood(dataclasses.replace(data, increments=noisy)).shape_departure(truth)
    assert found.p_value < 1e-6
    worst = found.at_increment
    assert abs(found.max_relative - g[worst]) < 4 * found.max_relative_sd
    assert abs(found.max_relative) > 0.8 * np.max(np.abs(g))
    assert "depart from the law" in found.describe()
    # in Π itself: the injected departure g × the law's increment, where that is largest
    injected = g * model
    at = int(np.argmax(np.abs(found.relative * model)))
    assert abs(found.max_absolute - injected[at]) < 4 * found.max_absolute_sd
    assert abs(found.max_absolute) > 0.8 * np.max(np.abs(injected))
    assert found.largest == np.max(np.abs(model)) and found.reference == model[worst]
