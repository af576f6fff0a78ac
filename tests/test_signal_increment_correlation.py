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
from test_signal_integrated_noise import (
    ACCELERATION_NOISE,
    FREQUENCY_HZ,
    _dry_motion,  # the same dry-friction rig, simulated with solve_ivp
)

from bayestribo.io.acceleration import from_acceleration
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.increments import increment_weights, integrate_increments, pi_data
from bayestribo.signal.noise import noise_model

pytestmark = pytest.mark.slow  # 20 records, each integrated with its noise drawn: ~6 s CPU

BIAS = 0.2  # [m/s²]
DRAWS = 20


def _errors(
    t: np.ndarray, x: np.ndarray, v: np.ndarray, acceleration: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One record's increments' errors over their standard deviations, the correlation
    of their noise model, and the equilibrium's line over the same."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the integration is said with a warning
        run = from_acceleration(t, acceleration)
        decay = energy_decay(run.time, velocity=run.velocity, frequency_Hz=FREQUENCY_HZ)
    assert decay.derived_channel == "displacement"
    sc = decay.scaling
    first = int(np.searchsorted(t, decay.t[0]))
    span = slice(first, first + decay.t.size)
    y, yp = x[span] / sc.length_scale, v[span] / (sc.length_scale * sc.omega)
    data = pi_data(decay, noise_model(decay, dict(run.metadata)), motion=(y, yp), n_replicates=100)
    edges, weights = increment_weights(
        decay.tau.size, decay.tau[1] - decay.tau[0], data.preparation["grid_points"]
    )
    error = data.increments - integrate_increments(0.5 * (y * y + yp * yp), edges, weights)
    sd = np.sqrt(data.variance)
    correlation = getattr(data, "correlation", None)
    if correlation is None:  # independent increments
        correlation = np.eye(error.size)
    return error / sd, correlation, data.offset_design[:, :2] / sd[:, None], sd


def _whitened(
    standardized: np.ndarray, correlation: np.ndarray, line: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The errors whitened with ``correlation``, the equilibrium's line taken out, and
    the covariance I - H they then have if the model is right."""
    chol = np.linalg.cholesky(correlation)
    white = np.linalg.solve(chol, standardized)
    line = np.linalg.solve(chol, line)
    hat = line @ np.linalg.solve(line.T @ line, line.T)
    return white - hat @ white, np.eye(white.size) - hat


@pytest.fixture(scope="module")
def whitened_errors() -> dict[bool, list[tuple[np.ndarray, np.ndarray]]]:
    """Per draw of the accelerometer's record, the whitened increments' errors and
    their covariance if the noise model is right: with the increments' correlation
    (True) and with the increments taken as independent (False)."""
    t, x, v, a = _dry_motion()
    rng = np.random.default_rng(2026)
    out: dict[bool, list[tuple[np.ndarray, np.ndarray]]] = {True: [], False: []}
    for _ in range(DRAWS):
        noisy = a + BIAS + ACCELERATION_NOISE * rng.standard_normal(t.size)
        standardized, correlation, line, _ = _errors(t, x, v, noisy)
        out[True].append(_whitened(standardized, correlation, line))
        out[False].append(_whitened(standardized, np.eye(standardized.size), line))
    return out


def test_whitened_errors_have_their_variance(whitened_errors):
    ratio = np.concatenate([z * z / np.diag(c) for z, c in whitened_errors[True]])
    # ~300 terms: a standard error of about √(2/300) = 0.08 for independent ones
    assert ratio.size > 250
    assert np.mean(ratio) == pytest.approx(1.0, abs=3.0 * math.sqrt(2.0 / ratio.size))


def test_whitened_neighbours_are_uncorrelated(whitened_errors):
    for correlated in (True, False):
        excess = np.concatenate(
            [z[:-1] * z[1:] - np.diag(c, 1) for z, c in whitened_errors[correlated]]
        )
        # each product has a standard deviation of about 1: the mean's error 1/√n
        uncorrelated = abs(np.mean(excess)) < 3.0 / math.sqrt(excess.size)
        # the increments taken as independent: -0.6 between neighbours
        assert uncorrelated == correlated, np.mean(excess)


def _runs(pairs: list[tuple[np.ndarray, np.ndarray]]) -> float:
    """Mean ratio of the square of a sum of four neighbouring terms to its variance
    (1 when the model holds)."""
    ones = np.ones(4)
    ratios = []
    for z, c in pairs:
        for start in range(0, z.size - 3, 4):
            part = slice(start, start + 4)
            ratios.append(z[part].sum() ** 2 / (ones @ c[part, part] @ ones))
    return float(np.mean(ratios))


def test_runs_of_increments_have_about_their_variance(whitened_errors):
    # A run of increments is what a decay rate is measured from. Taken as independent,
    # a run of four has 0.4 times the variance the model gives it (intervals too
    # wide); with the correlation 1.3-1.5 times (the whitening brings out what the
    # Monte Carlo does not hold along the runs, and the ratio's standard error over
    # ~80 runs is √(2/80) = 0.16): the error of the runs' variance, in log, at least
    # halved.
    correlated, independent = _runs(whitened_errors[True]), _runs(whitened_errors[False])
    assert independent < 0.6
    assert abs(math.log(correlated)) < 0.5 * abs(math.log(independent)), (correlated, independent)
