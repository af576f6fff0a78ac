"""The noise of a displacement integrated from a recorded velocity, against simulation.

An independent record (scipy's ``solve_ivp`` of ẍ + 2ζωẋ + ω²x + q ẋ|ẋ| = 0, nothing
from the package) is recorded as a velocity alone with white noise, many times over
with the same motion. Each draw's Π increments are compared with the motion's own
(∫E of the noise-free channels, on the decay's grid), less the equilibrium's line
the likelihood marginalises (the first two columns of ``offset_design``). The
standardised errors must have mean 0 and variance 1 where the noise model says so: the
integrated noise is a random walk, of which the decay keeps only the departure from a
line, the equilibrium and its drift taking the line.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bayestribo.signal.decay import energy_decay
from bayestribo.signal.increments import increment_weights, integrate_increments, pi_data
from bayestribo.signal.noise import noise_model

FREQUENCY_HZ = 2.5
ZETA, DRAG, X0 = 0.01, 1.0, 0.04  # [-], [1/m], [m]
RATE_HZ, REST_S, DURATION_S = 200.0, 2.0, 12.0
VELOCITY_NOISE = 2e-3  # [m/s], 1/600 of the first swing's peak velocity
DRAWS = 24


def _motion() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    omega = 2.0 * math.pi * FREQUENCY_HZ

    def rhs(_t: float, s: np.ndarray) -> list[float]:
        return [s[1], -2 * ZETA * omega * s[1] - omega**2 * s[0] - DRAG * s[1] * abs(s[1])]

    sol = solve_ivp(rhs, (0.0, DURATION_S), [X0, 0.0], rtol=1e-11, atol=1e-13, dense_output=True)
    t = np.arange(0.0, REST_S + DURATION_S, 1.0 / RATE_HZ)
    x, v = np.full(t.size, X0), np.zeros(t.size)
    moving = t >= REST_S
    x[moving], v[moving] = sol.sol(t[moving] - REST_S)
    return t, x, v


@pytest.fixture(scope="module")
def standardised_errors() -> list[np.ndarray]:
    """Per draw, the increments' errors over their modelled standard deviations."""
    t, x, v = _motion()
    out = []
    for seed in range(DRAWS):
        noisy = v + VELOCITY_NOISE * np.random.default_rng(seed).standard_normal(t.size)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the decay fades into the noise: said, expected
            decay = energy_decay(t, velocity=noisy, frequency_Hz=FREQUENCY_HZ)
        assert decay.derived_channel == "displacement"
        sc = decay.scaling
        first = int(np.searchsorted(t, decay.t[0]))
        span = slice(first, first + decay.t.size)
        y, yp = x[span] / sc.length_scale, v[span] / (sc.length_scale * sc.omega)
        data = pi_data(decay, noise_model(decay, {}), motion=(y, yp))
        edges = np.searchsorted(decay.tau, data.tau_grid)
        _, weights = increment_weights(decay.tau.size, decay.tau[1] - decay.tau[0], edges.size - 1)
        error = data.increments - integrate_increments(0.5 * (y * y + yp * yp), edges, weights)
        line = data.offset_design[:, :2]
        w = 1.0 / data.variance
        coef = np.linalg.solve((line.T * w) @ line, (line.T * w) @ error)
        out.append((error - line @ coef) / np.sqrt(data.variance))
    return out


def _late(errors: list[np.ndarray]) -> np.ndarray:
    """The second half of every draw's increments: where the walk has wandered furthest
    from where it started and the noise weighs most against the swing."""
    return np.concatenate([z[z.size // 2 :] for z in errors])


def test_integrated_noise_variance_matches_simulation(standardised_errors):
    z = _late(standardised_errors)
    # χ²/n of ~700 terms: a standard error of about √(2/700) = 0.05 for independent ones
    assert np.mean(z * z) == pytest.approx(1.0, abs=0.2)


def test_integrated_noise_bias_is_removed(standardised_errors):
    # the mean of each draw's late errors: independent across draws
    means = np.array([z[z.size // 2 :].mean() for z in standardised_errors])
    se = means.std(ddof=1) / math.sqrt(means.size)
    assert abs(means.mean()) < 3.0 * se
