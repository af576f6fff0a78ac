"""Π increments and their noise: quadrature, noise propagation, exact correlation."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from bayestribo.signal.decay import energy_decay
from bayestribo.signal.increments import increment_weights, pi_data, simpson_weights
from bayestribo.signal.noise import noise_model, resolution_for_range
from bayestribo.synthetic import Sensor
from bayestribo.synthetic.recording import simulate


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 8, 11])
def test_quadrature_weights_are_exact_for_cubics(n):
    h = 0.1
    w = simpson_weights(n, h)
    x = np.linspace(0.0, n * h, n + 1)
    degree = 1 if n == 1 else 3  # the trapezoidal rule is exact for lines only
    for k in range(degree + 1):
        assert w @ x**k == pytest.approx((n * h) ** (k + 1) / (k + 1), rel=1e-12, abs=1e-15)


def test_grid_covers_every_sample_once():
    edges, weights = increment_weights(1001, 0.02, 64)
    assert edges[0] == 0 and edges[-1] == 1000
    assert all(w.size == b - a + 1 for a, b, w in zip(edges[:-1], edges[1:], weights, strict=True))
    assert sum(w.sum() for w in weights) == pytest.approx(1000 * 0.02)


@pytest.fixture(scope="module")
def clean_decay():
    run = simulate(
        sensor=Sensor(displacement_noise_m=0.0, velocity_noise_m_per_s=0.0, sample_rate_Hz=5000.0),
        seed=4,
    )
    return run, energy_decay(run.time, run.displacement, run.velocity, rig=run.rig())


def test_increment_variance_matches_monte_carlo(clean_decay):
    """The analytic Var(D_j) and noise bias against 600 noisy copies of the same record."""
    _, decay = clean_decay
    sigma_x, sigma_v = 3e-6, 3e-7  # 20× the resolution
    noise = noise_model(decay, displacement_resolution=sigma_x, velocity_resolution=sigma_v)
    data = pi_data(decay, noise, grid_points=32)
    edges, weights = increment_weights(decay.tau.size, decay.tau[1] - decay.tau[0], 32)
    sc = decay.scaling
    rng = np.random.default_rng(5)
    draws = []
    for _ in range(600):
        y = decay.y + rng.normal(0, sigma_x / sc.length_scale, decay.y.size)
        yp = decay.yp + rng.normal(0, sc.yp(sigma_v), decay.y.size)
        e = 0.5 * (y * y + yp * yp)
        draws.append(
            [w @ e[a : b + 1] for a, b, w in zip(edges[:-1], edges[1:], weights, strict=True)]
        )
    draws = np.asarray(draws)
    clean = np.array(
        [
            w @ decay.energy[a : b + 1]
            for a, b, w in zip(edges[:-1], edges[1:], weights, strict=True)
        ]
    )
    # Sample variance of 600 draws: relative standard error √(2/599) = 5.8 %; 4σ. The
    # last increment also carries the end-of-motion allowance, checked separately.
    np.testing.assert_allclose(draws.var(axis=0, ddof=1)[:-1], data.variance[:-1], rtol=0.24)
    assert data.variance[-1] > draws.var(axis=0, ddof=1)[-1]
    # The bias ½(σ_y² + σ_y'²)∫1 against the mean shift (5 standard errors).
    se = np.sqrt(data.variance / 600)
    assert np.all(np.abs(draws.mean(axis=0) - clean - data.noise_bias) < 5 * se)


def test_white_noise_neighbours_share_their_boundary_sample():
    """At 1 kHz (31 samples per period, the independent solve_ivp simulator) the sample
    two increments share correlates them by up to 1e-2; pi_data's covariances against
    the dense covariance matrix of the increments and against 20000 noisy copies."""
    from test_signal_frontend import RIG, record

    t, x, v, _, _ = record(1000.0, 0.1, 0.1)
    decay = energy_decay(t, x, v, rig=RIG)
    sigma_x, sigma_v = 1.5e-6, 1.5e-7  # 10x the resolution
    noise = noise_model(decay, displacement_resolution=sigma_x, velocity_resolution=sigma_v)
    m = 31
    data = pi_data(decay, noise, grid_points=m)
    edges, weights = increment_weights(decay.tau.size, decay.tau[1] - decay.tau[0], m)
    np.testing.assert_array_equal(data.tau_grid, decay.tau[edges])
    sc = decay.scaling
    sy, syp = sigma_x / sc.length_scale, sc.yp(sigma_v)
    # dense: Σ = W diag(Var E_i) Wᵀ, W the (m, samples) matrix of quadrature weights
    dense_w = np.zeros((m, decay.tau.size))
    for j, (a, b, w) in enumerate(zip(edges[:-1], edges[1:], weights, strict=True)):
        dense_w[j, a : b + 1] = w
    var_e = decay.y**2 * sy**2 + decay.yp**2 * syp**2 + 0.5 * (sy**4 + syp**4)
    cov = (dense_w * var_e) @ dense_w.T
    np.testing.assert_allclose(data.neighbour_covariance, np.diag(cov, 1), rtol=1e-10)
    assert np.count_nonzero(np.triu(cov, 2)) == 0  # only neighbours share a sample
    corr = np.diag(cov, 1) / np.sqrt(np.diag(cov)[:-1] * np.diag(cov)[1:])
    assert corr.max() > 5e-3  # material at 1 kHz (about 1e-3 at 10 kHz)
    # each increment gets both neighbours' covariance: a run of increments is not
    # understated (the last increment carries the end-of-motion allowance besides)
    own = np.diag(cov) + np.r_[0.0, np.diag(cov, 1)] + np.r_[np.diag(cov, 1), 0.0]
    np.testing.assert_allclose(data.variance[:-1], own[:-1], rtol=1e-10)
    assert data.variance[:-1].sum() >= cov[:-1, :-1].sum() * (1 - 1e-12)
    # Monte Carlo: the mean neighbour correlation of 20000 copies (standard error
    # about 1/√(20000·30) = 1.3e-3, the correlations about 8e-3)
    rng = np.random.default_rng(7)
    draws = []
    for _ in range(20):
        y = decay.y + rng.normal(0.0, sy, (1000, decay.y.size))
        yp = decay.yp + rng.normal(0.0, syp, (1000, decay.y.size))
        draws.append(0.5 * (y * y + yp * yp) @ dense_w.T)
    draws = np.concatenate(draws)
    mc = np.corrcoef(draws[:, :-1], rowvar=False)
    mc_corr = np.diag(mc, 1)
    se = 1.0 / np.sqrt(draws.shape[0] * mc_corr.size)
    assert abs(mc_corr.mean() - corr[:-1].mean()) < 4 * se
    assert mc_corr.mean() > 4 * se


def test_correlated_pi_likelihood_equals_increment_likelihood():
    """Π with covariance V(max(k, l)) is a backward random walk of independent increments."""
    rng = np.random.default_rng(6)
    m = 12
    var = rng.uniform(0.5, 2.0, m)
    model_inc = rng.uniform(1.0, 3.0, m)
    obs_inc = model_inc + rng.normal(0, np.sqrt(var))
    pi_obs = np.cumsum(obs_inc[::-1])[::-1]
    pi_model = np.cumsum(model_inc[::-1])[::-1]
    tail_var = np.cumsum(var[::-1])[::-1]
    k = np.arange(m)
    cov = tail_var[np.maximum.outer(k, k)]
    dense = multivariate_normal(pi_model, cov).logpdf(pi_obs)
    increments = np.sum(-0.5 * ((obs_inc - model_inc) ** 2 / var + np.log(2 * np.pi * var)))
    assert dense == pytest.approx(increments, rel=1e-12)


def test_derived_velocity_noise_against_the_whole_pipeline():
    """Monte Carlo propagation through the derivative against re-running energy_decay."""
    sigma = 2e-6
    base = simulate(
        sensor=Sensor(
            displacement_noise_m=0.0,
            velocity_noise_m_per_s=0.0,
            sample_rate_Hz=4000.0,
            channels=("displacement",),
        ),
        seed=8,
    )
    decay = energy_decay(base.time, base.displacement, rig=base.rig())
    noise = noise_model(decay, displacement_resolution=sigma)
    data = pi_data(decay, noise, grid_points=16, n_replicates=300, seed=1)
    edges, weights = increment_weights(decay.tau.size, decay.tau[1] - decay.tau[0], 16)
    rng = np.random.default_rng(9)
    draws = []
    for _ in range(60):
        noisy = base.displacement + rng.normal(0, sigma, base.displacement.size)
        d = energy_decay(base.time, noisy, rig=base.rig())
        # Same time stamps: integrate the re-processed E over the same sample ranges.
        idx = np.searchsorted(d.t, decay.t[edges[:9]])
        if idx[0] >= d.t.size or not np.array_equal(d.t[idx], decay.t[edges[:9]]):
            continue
        draws.append(
            [w @ d.energy[i : i + w.size] for i, w in zip(idx[:8], weights[:8], strict=True)]
        )
    draws = np.asarray(draws)
    assert len(draws) >= 30
    # The pipeline also re-estimates the equilibrium and the frequency, which the
    # likelihood's nuisance terms absorb: compare the early increments, where the
    # derivative's noise dominates, within the sampling error of ~40 draws (±45 %).
    ratio = draws.var(axis=0, ddof=1)[:8] / data.variance[:8]
    assert np.all((ratio > 0.45) & (ratio < 2.2)), ratio


def test_noise_model_uses_the_larger_figure_and_says_so():
    run = simulate(
        sensor=Sensor(displacement_noise_m=30 * 1.5e-7, velocity_noise_m_per_s=1.5e-8), seed=3
    )
    decay = energy_decay(run.time, run.displacement, run.velocity, rig=run.rig())
    noise = noise_model(decay, run.metadata)
    assert noise.source_displacement == "measured" and noise.exceeds_nominal
    assert noise.displacement == pytest.approx(30 * 1.5e-7, rel=0.1)
    assert noise.source_velocity in ("nominal", "measured")
    ratio = noise.displacement / noise.nominal_displacement
    assert f"{ratio:.3g}× the resolution" in noise.describe()


def test_resolution_table_scales_with_range():
    assert resolution_for_range("displacement", 10e-3) == pytest.approx(0.15e-6)
    assert resolution_for_range("velocity", 0.5) == pytest.approx(0.0075e-6)
    with pytest.raises(ValueError, match="channel"):
        resolution_for_range("force", 1.0)


@pytest.mark.parametrize("n", range(1, 10))
def test_simpson_weights_integrate_polynomials_exactly(n):
    # Simpson and the 3/8 rule are exact for cubics; the lone trapezoid (n = 1) for lines.
    from bayestribo.signal.increments import simpson_weights

    h = 0.37
    x = 1.3 + h * np.arange(n + 1)
    w = simpson_weights(n, h)
    degree = 1 if n == 1 else 3
    for k in range(degree + 1):
        exact = (x[-1] ** (k + 1) - x[0] ** (k + 1)) / (k + 1)
        assert w @ x**k == pytest.approx(exact, rel=1e-12)


def test_derived_channel_noise_agrees_with_the_linearised_propagation():
    # Velocity recorded, displacement integrated from it: the change of each
    # increment is, to first order, a_j·η with a_j = Cᵀ(w_j y) + w_j y' (C the
    # cumulative-trapezoid matrix less its least-squares line in τ, which the
    # equilibrium and its drift take), so its variance is σ²|a_j|², computed here by
    # linear algebra independently of the Monte Carlo in increment_noise.
    from bayestribo.signal.increments import increment_noise, increment_weights

    n = 201
    tau = np.linspace(0.0, 4 * np.pi, n)
    y, yp = np.cos(tau) * np.exp(-0.05 * tau), -np.sin(tau) * np.exp(-0.05 * tau)
    edges, weights = increment_weights(n, float(tau[1] - tau[0]), 8)
    sigma = 1e-4
    bias, var = increment_noise(
        tau, y, yp, edges, weights, 0.0, sigma, derived="displacement", n_replicates=4000, seed=3
    )
    h = tau[1] - tau[0]
    cum = np.zeros((n, n))  # δy_i = Σ_k C_ik η_k, trapezoid from sample 0
    for i in range(1, n):
        cum[i, : i + 1] = h
        cum[i, 0] = cum[i, i] = h / 2
    line = np.column_stack([np.ones(n), tau])
    cum -= line @ np.linalg.lstsq(line, cum, rcond=None)[0]
    expected, expected_bias = [], []
    dy2 = sigma**2 * np.sum(cum * cum, axis=1)  # Var δy_i
    for a, b, w in zip(edges[:-1], edges[1:], weights, strict=True):
        wy, wyp = np.zeros(n), np.zeros(n)
        wy[a : b + 1], wyp[a : b + 1] = w * y[a : b + 1], w * yp[a : b + 1]
        expected.append(sigma**2 * np.sum((cum.T @ wy + wyp) ** 2))
        # the mean change is second order: ½ Σ w (Var δy + σ²)
        expected_bias.append(0.5 * w @ (dy2[a : b + 1] + sigma**2))
    expected = np.asarray(expected)
    # 4000 replicates: relative sd of a variance estimate √(2/4000) ≈ 2.2 %.
    np.testing.assert_allclose(var, expected, rtol=0.1)
    # the mean's Monte Carlo error is √(var/4000): 5 of them
    assert np.all(np.abs(bias - expected_bias) < 5 * np.sqrt(expected / 4000))


def test_white_noise_at_rest_keeps_the_white_variances():
    # A simulated record with white noise: the rest spectrum is not flagged coloured
    # and the increments' variances are exactly the white formula's.
    run = simulate(
        sensor=Sensor(displacement_noise_m=20 * 1.5e-7, velocity_noise_m_per_s=20 * 1.5e-8),
        seed=12,
    )
    decay = energy_decay(run.time, run.displacement, run.velocity, rig=run.rig())
    assert decay.rest_noise is not None and not decay.rest_noise.coloured
    noise = noise_model(decay, run.metadata)
    np.testing.assert_array_equal(
        pi_data(decay, noise).variance, pi_data(decay, noise, spectral=False).variance
    )
