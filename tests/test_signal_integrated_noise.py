"""The noise of an integrated record, against simulation.

Independent records (scipy's ``solve_ivp``, nothing from the package) are recorded
many times over with the same motion: ẍ + 2ζωẋ + ω²x + q ẋ|ẋ| = 0 as a velocity alone
with white noise, and ẍ + 2ζωẋ + ω²x + μg sgn ẋ = 0, sticking, as an accelerometer's
record (the mean acceleration over each sample interval, a bias and white noise, with
rest before and after), integrated at reading. Each draw's Π increments are compared
with the motion's own (∫E of the noise-free channels, on the decay's grid), less the
equilibrium's line the likelihood marginalises (the first two columns of
``offset_design``). The standardised errors must have mean 0 and variance 1 where the
noise model says so:

* the noise of a displacement integrated from the velocity is a random walk, of which
  the decay keeps only the departure from a line, the equilibrium and its drift
  taking the line;
* an accelerometer's velocity is itself an integral, its drift taken off between the
  rests: its noise in the motion is larger than at rest, and only the integration put
  to the sensor's noise shows it.
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
ZETA, DRAG, X0 = 0.01, 1.0, 0.04  # [-], [1/m], [m]
RATE_HZ, REST_S, DURATION_S = 200.0, 2.0, 12.0
VELOCITY_NOISE = 2e-3  # [m/s], 1/600 of the first swing's peak velocity
DRAWS = 24
DRY_FRICTION, STICKING = 0.02, 1.3  # μ_k [-], μ_s/μ_k
REST_AFTER_S = 3.0
ACCELERATION_NOISE = 0.02  # [m/s²], 200 µg/√Hz at 200 Hz
ACCELEROMETER_DRAWS = 12


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


def _dry_motion() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Time, displacement, velocity and the mean acceleration over each sample
    interval of the dry-friction rig, at rest before the release and after the stop."""
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

    t = np.arange(0.0, REST_S + start + REST_AFTER_S, 1.0 / RATE_HZ)
    xs, vs = state(t - REST_S)
    h = 0.5 / RATE_HZ
    a = (state(t - REST_S + h)[1] - state(t - REST_S - h)[1]) / (2.0 * h)
    return t, xs, vs, a


def _standardised(
    t: np.ndarray, x: np.ndarray, v: np.ndarray, decay, metadata: dict, n_replicates: int
) -> np.ndarray:
    """One draw's increments' errors over their modelled standard deviations."""
    assert decay.derived_channel == "displacement"
    sc = decay.scaling
    first = int(np.searchsorted(t, decay.t[0]))
    span = slice(first, first + decay.t.size)
    y, yp = x[span] / sc.length_scale, v[span] / (sc.length_scale * sc.omega)
    data = pi_data(decay, noise_model(decay, metadata), motion=(y, yp), n_replicates=n_replicates)
    edges, weights = increment_weights(
        decay.tau.size, decay.tau[1] - decay.tau[0], data.preparation["grid_points"]
    )
    error = data.increments - integrate_increments(0.5 * (y * y + yp * yp), edges, weights)
    line = data.offset_design[:, :2]
    w = 1.0 / data.variance
    coef = np.linalg.solve((line.T * w) @ line, (line.T * w) @ error)
    return (error - line @ coef) / np.sqrt(data.variance)


@pytest.fixture(scope="module")
def standardised_errors() -> list[np.ndarray]:
    """Per draw of the velocity-only record, the standardised increments' errors."""
    t, x, v = _motion()
    out = []
    for seed in range(DRAWS):
        noisy = v + VELOCITY_NOISE * np.random.default_rng(seed).standard_normal(t.size)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the decay fades into the noise: said, expected
            decay = energy_decay(t, velocity=noisy, frequency_Hz=FREQUENCY_HZ)
        out.append(_standardised(t, x, v, decay, {}, 300))
    return out


@pytest.fixture(scope="module")
def accelerometer_errors() -> list[np.ndarray]:
    """Per draw of the accelerometer's record, the standardised increments' errors."""
    t, x, v, a = _dry_motion()
    out = []
    for seed in range(ACCELEROMETER_DRAWS):
        noisy = a + 0.2 + ACCELERATION_NOISE * np.random.default_rng(seed).standard_normal(t.size)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the integration is said with a warning
            run = from_acceleration(t, noisy)
            decay = energy_decay(run.time, velocity=run.velocity, frequency_Hz=FREQUENCY_HZ)
        # 100 replicates: each variance known to ±14 %, the mean of 150 to ±2 %
        out.append(_standardised(t, x, v, decay, dict(run.metadata), 100))
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


def test_accelerometer_noise_variance_matches_simulation(accelerometer_errors):
    z = np.concatenate(accelerometer_errors)
    # χ²/n of ~170 terms: a standard error of about √(2/170) = 0.11 for independent ones
    assert np.mean(z * z) == pytest.approx(1.0, abs=0.3)


def test_accelerometer_noise_bias_is_removed(accelerometer_errors):
    means = np.array([z.mean() for z in accelerometer_errors])
    se = means.std(ddof=1) / math.sqrt(means.size)
    assert abs(means.mean()) < 3.0 * se
