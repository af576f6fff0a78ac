"""The second pass: increment variances from the law's motion at the optimum."""

from __future__ import annotations

import itertools
import math
import warnings

import numpy as np
import pytest
from _law_recording import law_recording
from scipy.integrate import solve_ivp

from bayestribo.inference.pipeline import build_posterior, find_optimum, prepare
from bayestribo.inference.reweight import law_motion, reweighted_posterior
from bayestribo.inference.start import maximum_from
from bayestribo.model.laws import get_law
from bayestribo.signal.increments import increment_noise, increment_weights, noise_bias_sd

OMEGA = 2.0 * math.pi * 32.6


def _coulomb_motion(mu: float, y0: float, tau: np.ndarray) -> np.ndarray:
    """y(τ), y'(τ) (shape (2, n)) of ÿ + y = -μ sgn ẏ from rest at y0 (μ_s = μ_k), by
    solve_ivp half cycle by half cycle, at rest once a turning point is within ±μ."""
    out = np.zeros((2, tau.size))
    start, y, t0 = 0, y0, 0.0
    while start < tau.size:
        if abs(y) <= mu:
            out[0, start:] = y
            break
        force = -mu * math.copysign(1.0, -y)  # moving towards the other side

        def rhs(_t, s, f=force):
            return [s[1], -s[0] + f]

        def turned(_t, s):
            return s[1]

        turned.terminal, turned.direction = True, (1.0 if y > 0 else -1.0)
        sol = solve_ivp(
            rhs,
            (t0, t0 + 2 * math.pi),
            [y, 0.0],
            events=turned,
            dense_output=True,
            rtol=1e-11,
            atol=1e-13,
        )
        t1 = float(sol.t_events[0][0])
        stop = int(np.searchsorted(tau, t1, side="right"))
        if stop > start:
            out[:, start:stop] = sol.sol(tau[start:stop])
        start, y, t0 = stop, float(sol.y_events[0][0][0]), t1
    return out


def test_law_motion_is_the_coulomb_solution():
    """Coulomb friction's half cycles are half cosines about ±μ: the motion rebuilt
    from the law's turning points is the ODE's, to the integrator's accuracy, and at
    rest after the stop."""
    tau = np.linspace(0.0, 40.0, 4001)
    mu = 0.07
    y, yp = law_motion(get_law("coulomb"), {"mu_k": mu, "mu_s_ratio": 1.0}, 1.0, 0.0, tau)
    ref = _coulomb_motion(mu, 1.0, tau)
    assert np.max(np.abs(y - ref[0])) < 1e-6
    assert np.max(np.abs(yp - ref[1])) < 1e-6
    moving = np.flatnonzero(np.abs(np.diff(ref[0])) > 0)
    assert moving[-1] < tau.size - 100  # the record holds the rest after the stop
    assert np.all(yp[moving[-1] + 2 :] == 0.0)


def test_law_motion_of_a_drag_holds_each_half_cycles_square_within_a_few_per_cent():
    """For viscous + quadratic drag the half cosines are an approximation: Σy² and
    Σy'² over each half cycle (what the increments' variances need) within 3 % of
    solve_ivp's."""
    zeta, c2 = 0.01, 0.05
    law = get_law("viscous+quadratic")
    values = {"zeta": zeta, "c2": c2}
    tau = np.linspace(0.0, 10 * math.pi, 20001)
    y, yp = law_motion(law, values, 1.0, 0.0, tau, reference=1.0)
    ref = solve_ivp(
        lambda _t, s: [s[1], -s[0] - 2 * zeta * s[1] - c2 * s[1] * abs(s[1])],
        (0.0, tau[-1]),
        [1.0, 0.0],
        t_eval=tau,
        rtol=1e-11,
        atol=1e-13,
    ).y
    law_turns = law.turning_points(values, 1.0, 0.0, tau_max=tau[-1], reference=1.0)[0]
    for a, b in itertools.pairwise(law_turns):
        part = (tau >= a) & (tau < b)
        for mine, theirs in ((y, ref[0]), (yp, ref[1])):
            assert np.sum(mine[part] ** 2) == pytest.approx(np.sum(theirs[part] ** 2), rel=0.03)


def test_law_motion_starting_in_motion_starts_at_the_initial_state():
    """A record that starts mid-motion: the first half cosine continued backwards
    passes near (y0, y'0)."""
    tau = np.linspace(0.0, 20.0, 2001)
    y, yp = law_motion(get_law("viscous"), {"zeta": 0.005}, 0.6, 0.8, tau)
    assert y[0] == pytest.approx(0.6, abs=0.02)
    assert yp[0] == pytest.approx(0.8, abs=0.02)


def _record(seed: int):
    return law_recording(
        lambda v: 2 * 0.01 * OMEGA * v,
        x0=1.5e-3,
        load_N=None,
        noise_x=30 * 1.5e-7,
        noise_v=30 * 1.5e-8,
        duration_s=4.0,
        seed=seed,
    )


def _chi2(posterior, theta) -> tuple[float, int]:
    params = posterior.physical(np.asarray(theta)[None])["params"]
    r = posterior.likelihood.standardized_residuals(params)
    return float(np.sum(r**2)), r.size


@pytest.mark.validation  # six records fitted: a calibration of the variances
def test_second_pass_variances_make_chi2_per_increment_one():
    """Six independent records (solve_ivp) at 30 times the vibrometer's resolution:
    with the observed channels the tail's variances are too large (χ² per increment
    at the optimum about 0.76); from the law's motion it is 1 (its sd over the ~1600
    increments is 0.036)."""
    first, second = [0.0, 0], [0.0, 0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for seed in range(6):
            prepared = prepare(_record(seed))
            posterior = build_posterior(prepared.data, law="viscous", friction=False)
            theta = find_optimum(posterior, prepared.decay)[0]
            posterior2 = reweighted_posterior(posterior, prepared.decay, theta)
            data2 = posterior2.likelihood.data
            np.testing.assert_array_equal(data2.increments, prepared.data.increments)
            assert posterior2.names == posterior.names
            theta2 = maximum_from(posterior2, theta, prepared.decay)[0]
            for total, (chi2, m) in (
                (first, _chi2(posterior, theta)),
                (second, _chi2(posterior2, theta2)),
            ):
                total[0] += chi2
                total[1] += m
    assert first[0] / first[1] < 0.85
    assert second[0] / second[1] == pytest.approx(1.0, abs=0.1)


def test_variances_from_the_given_motion_follow_the_white_formula():
    """pi_data's variances with ``motion`` are the white formula on those channels
    (plus the shared sample's covariance), whatever the observed channels hold."""
    prepared = prepare(_record(0))
    decay, noise = prepared.decay, prepared.noise
    from bayestribo.signal.increments import pi_data

    y, yp = 0.5 * decay.y, 0.5 * decay.yp
    data = pi_data(decay, noise, motion=(y, yp))
    h = float(decay.tau[1] - decay.tau[0])
    edges, weights = increment_weights(decay.tau.size, h, data.increments.size)
    sc = decay.scaling
    sy, syp = noise.displacement / sc.length_scale, noise.velocity / (sc.length_scale * sc.omega)
    _, white = increment_noise(decay.tau, y, yp, edges, weights, sy, syp)
    plus = np.maximum(data.neighbour_covariance, 0.0)
    np.testing.assert_allclose(
        data.variance, white + np.r_[0.0, plus] + np.r_[plus, 0.0], rtol=1e-12
    )
    with pytest.raises(ValueError, match="motion"):
        pi_data(decay, noise, motion=(y[:-1], yp[:-1]))


def test_noise_bias_sd_is_that_of_a_variance_measured_on_the_rest():
    """σ² measured on n samples of rest is known to √(2/n); the displacement's noise
    dominates E's bias here, so the relative sd of the bias is that."""
    prepared = prepare(_record(0))
    decay, noise = prepared.decay, prepared.noise
    assert noise.source_displacement == "measured"
    n = decay.noise.n_samples
    assert n > 100
    assert noise_bias_sd(decay, noise) == pytest.approx(math.sqrt(2.0 / n), rel=0.02)
    col = prepared.data.offset_design[:, 2]
    np.testing.assert_allclose(col, prepared.data.noise_bias * noise_bias_sd(decay, noise))


def test_noise_bias_sd_of_a_nominal_level_spans_what_was_measured():
    """A nominal resolution used above the noise measured at rest: the bias removed
    could be the measured noise's as well, so its standard error is at least their
    difference (here the nominal σ is twice the measured: 3/4 of its σ²)."""
    import dataclasses

    prepared = prepare(_record(0))
    decay, noise = prepared.decay, prepared.noise
    measured = noise.measured_displacement
    nominal = dataclasses.replace(
        noise,
        displacement=2.0 * measured,
        nominal_displacement=2.0 * measured,
        source_displacement="nominal",
    )
    sc = decay.scaling
    sy2 = (2.0 * measured / sc.length_scale) ** 2
    syp2 = (noise.velocity / (sc.length_scale * sc.omega)) ** 2
    rel_v = math.sqrt(2.0 / decay.noise.n_samples)
    expected = math.hypot(0.75 * sy2, rel_v * syp2) / (sy2 + syp2)
    assert noise_bias_sd(decay, nominal) == pytest.approx(expected, rel=1e-12)
    assert noise_bias_sd(decay, nominal) > 0.7
