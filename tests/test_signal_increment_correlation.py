"""The correlation of an integrated record's increments, against simulation.

An independent record (scipy's ``solve_ivp`` half cycle by half cycle, nothing from
the package) of ẍ + 2ζωẋ + ω²x + μg sgn ẋ = 0, sticking where the spring cannot
overcome μ_s, is recorded many times over as an accelerometer's record (the mean
acceleration over each sample interval, a bias and white noise, with rest before and
after); the package integrates the velocity from it at reading and the displacement
from the velocity. Each draw's Π increments are compared with the motion's own (∫E of
the noise-free channels on the decay's grid) and whitened with the noise model of the
increments (their variances and correlation,
:mod:`bayestribo.signal.increment_correlation`), the equilibrium's line (the first two
columns of ``offset_design``, which the likelihood marginalises) taken out by least
squares in the whitened space. If the noise model is right the whitened errors have
the covariance I - H, H the hat matrix of the line: variances 1 - h_jj and
neighbours' covariance -h_j,j+1. The integrated noise alternates about a slowly
varying level: with the increments taken as independent the neighbours' correlation
is about -0.6 and a run of four increments has 0.4 times the sum of their variances.

A velocity recorded alone with white noise at 40 samples a period (the displacement
its integral about the equilibrium's line) leaves its increments nearly independent
(lag-1 correlation 0.01 over 90 draws): that record is not where the correlation is.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bayestribo.io.acceleration import from_acceleration
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.increments import increment_weights, integrate_increments, pi_data
from bayestribo.signal.noise import noise_model

FREQUENCY_HZ = 2.5
STICKING = 1.3  # μ_s/μ_k
X0 = 0.04  # [m]
ZETA, DRY_FRICTION = 0.01, 0.02
RATE_HZ, REST_BEFORE_S, REST_AFTER_S = 200.0, 2.0, 3.0
ACCELERATION_NOISE = 0.02  # [m/s²], 200 µg/√Hz at 200 Hz
BIAS = 0.2  # [m/s²]
DRAWS = 16


def _motion() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Time, displacement, velocity and the mean acceleration over each sample
    interval of the rig at rest before the release, sliding, and stuck after its last
    turning point."""
    omega = 2.0 * math.pi * FREQUENCY_HZ
    mu_g = DRY_FRICTION * 9.81
    pieces, start, x = [], 0.0, X0
    while omega**2 * abs(x) > STICKING * mu_g:  # slides on from this turning point
        sign = -math.copysign(1.0, x)  # the direction of the coming half cycle

        def rhs(_t: float, s: np.ndarray, sign: float = sign) -> list[float]:
            return [s[1], -2 * ZETA * omega * s[1] - omega**2 * s[0] - sign * mu_g]

        def turn(_t: float, s: np.ndarray) -> float:
            return s[1]

        turn.terminal, turn.direction = True, -sign
        sol = solve_ivp(
            rhs,
            (start, start + 1.0),
            [x, 0.0],
            rtol=1e-11,
            atol=1e-13,
            dense_output=True,
            events=turn,
        )
        end = float(sol.t_events[0][0])
        pieces.append((start, end, sol.sol))
        start, x = end, float(sol.y_events[0][0][0])

    def state(times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        xs, vs = np.full(times.size, X0), np.zeros(times.size)
        for lo, hi, sol in pieces:
            inside = (times >= lo) & (times < hi)
            xs[inside], vs[inside] = sol(times[inside])
        xs[times >= start] = x
        return xs, vs

    t = np.arange(0.0, REST_BEFORE_S + start + REST_AFTER_S, 1.0 / RATE_HZ)
    xs, vs = state(t - REST_BEFORE_S)
    h = 0.5 / RATE_HZ  # the mean acceleration over each sample interval
    a = (state(t - REST_BEFORE_S + h)[1] - state(t - REST_BEFORE_S - h)[1]) / (2.0 * h)
    return t, xs, vs, a


def _whitened(
    t: np.ndarray, x: np.ndarray, v: np.ndarray, acceleration: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """One record's increments' errors whitened by their noise model, the equilibrium's
    line taken out, and the covariance I - H they then have if the model is right."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the integration is said with a warning
        run = from_acceleration(t, acceleration)
        decay = energy_decay(run.time, velocity=run.velocity, frequency_Hz=FREQUENCY_HZ)
    assert decay.derived_channel == "displacement"
    sc = decay.scaling
    first = int(np.searchsorted(t, decay.t[0]))
    span = slice(first, first + decay.t.size)
    y, yp = x[span] / sc.length_scale, v[span] / (sc.length_scale * sc.omega)
    data = pi_data(decay, noise_model(decay, dict(run.metadata)), motion=(y, yp))
    edges, weights = increment_weights(
        decay.tau.size, decay.tau[1] - decay.tau[0], data.preparation["grid_points"]
    )
    error = data.increments - integrate_increments(0.5 * (y * y + yp * yp), edges, weights)
    sd = np.sqrt(data.variance)
    correlation = getattr(data, "correlation", None)
    if correlation is None:  # independent increments
        correlation = np.eye(error.size)
    chol = np.linalg.cholesky(correlation)
    white = np.linalg.solve(chol, error / sd)
    line = np.linalg.solve(chol, data.offset_design[:, :2] / sd[:, None])
    hat = line @ np.linalg.solve(line.T @ line, line.T)
    return white - hat @ white, np.eye(error.size) - hat


@pytest.fixture(scope="module")
def whitened_errors() -> list[tuple[np.ndarray, np.ndarray]]:
    """Per draw of the accelerometer's record, the whitened increments' errors and
    their covariance if the noise model is right."""
    t, x, v, a = _motion()
    rng = np.random.default_rng(2026)
    return [
        _whitened(t, x, v, a + BIAS + ACCELERATION_NOISE * rng.standard_normal(t.size))
        for _ in range(DRAWS)
    ]


def test_whitened_errors_have_their_variance(whitened_errors):
    ratio = np.concatenate([z * z / np.diag(c) for z, c in whitened_errors])
    # ~250 terms: a standard error of about √(2/250) = 0.09 for independent ones
    assert ratio.size > 200
    assert np.mean(ratio) == pytest.approx(1.0, abs=0.25)


def test_whitened_neighbours_are_uncorrelated(whitened_errors):
    products = np.concatenate([z[:-1] * z[1:] for z, _ in whitened_errors])
    expected = np.concatenate([np.diag(c, 1) for _, c in whitened_errors])
    # each product has a standard deviation of about 1: the mean's error 1/√n = 0.065
    assert abs(np.mean(products - expected)) < 3.0 / math.sqrt(products.size)


def test_whitened_runs_have_the_variance_of_their_terms(whitened_errors):
    # sums of four neighbouring terms (a run of increments is what a decay rate is
    # measured from): their variance is the sum of their covariances
    ones = np.ones(4)
    ratios = []
    for z, c in whitened_errors:
        for start in range(0, z.size - 3, 4):
            part = slice(start, start + 4)
            ratios.append(z[part].sum() ** 2 / (ones @ c[part, part] @ ones))
    # ~60 sums: the mean ratio's standard error about √(2/60) = 0.18
    assert np.mean(ratios) == pytest.approx(1.0, abs=0.45)
