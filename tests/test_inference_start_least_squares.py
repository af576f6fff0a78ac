"""The start's Levenberg-Marquardt least squares (start._least_squares) against
scipy's ``least_squares``: MINPACK's ``lmder`` called the same way, through the
thinner ``leastsq`` wrapper, must give the same solution, residuals and Jacobian to
the bit, so that the optimum and the walkers drawn about it are unchanged."""

from __future__ import annotations

import numpy as np
import pytest
from _sim import simulate_flat
from scipy.optimize import least_squares

from bayestribo.inference import build_posterior, start
from bayestribo.inference.priors import Normal
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.increments import pi_data
from bayestribo.signal.noise import noise_model


@pytest.fixture(scope="module")
def data():
    run = simulate_flat(
        seed=6,
        zeta=0.0236,
        mu_k=0.0294,
        displacement_noise_m=1.5e-6,
        velocity_noise_m_per_s=1.5e-7,
        sample_rate_Hz=5000.0,
        offset_m=1e-4,
    )
    decay = energy_decay(run.time, run.displacement, run.velocity, rig=run.rig())
    return pi_data(decay, noise_model(decay, run.metadata), seed=0)


def _problems(data):
    """Residual functions of the start's kind: the standardized residuals of a
    posterior in the scaled steps of its continuous coordinates, from a point away from
    the optimum (the least squares then take many iterations)."""
    for kwargs in ({}, {"model": "averaged"}, {"priors": {"y0": Normal(0.0, 0.5)}}):
        post = build_posterior(data, **kwargs)
        free = [i for i, n in enumerate(post.names) if n != "mu_s_ratio"]
        values = {"zeta": 0.03, "mu_k": 0.01, "mu_s_ratio": 1.2, "y0": post.likelihood.data.y0}
        theta = np.array([values[n] for n in post.names])
        scale = 1e-3 * np.abs(theta[free])

        def residuals(u, post=post, theta=theta, free=free, scale=scale):
            th = theta.copy()
            th[free] = theta[free] + np.asarray(u) * scale
            return post.standardized_residuals(th[None], nuisances=True)[0]

        def jacobian(u, residuals=residuals):
            u = np.asarray(u, dtype=float)
            h = 1.5e-8 * np.maximum(1.0, np.abs(u))
            f0 = residuals(u)
            return np.column_stack(
                [(residuals(u + h[k] * np.eye(u.size)[k]) - f0) / h[k] for k in range(u.size)]
            )

        yield residuals, jacobian, len(free)


def test_the_least_squares_are_scipys_least_squares_to_the_bit(data):
    for residuals, jacobian, n in _problems(data):
        x, fun, jac = start._least_squares(residuals, jacobian, n, "lm")
        ref = least_squares(residuals, np.zeros(n), jac=jacobian, x_scale="jac", method="lm")
        assert np.max(np.abs(ref.x)) > 1.0  # the solution is away from the start
        np.testing.assert_array_equal(x, ref.x)
        np.testing.assert_array_equal(fun, ref.fun)
        np.testing.assert_array_equal(jac, ref.jac)


def test_other_methods_are_scipys_least_squares(data):
    residuals, jacobian, n = next(_problems(data))
    x, fun, jac = start._least_squares(residuals, jacobian, n, "trf")
    ref = least_squares(residuals, np.zeros(n), jac=jacobian, x_scale="jac", method="trf")
    np.testing.assert_array_equal(x, ref.x)
    np.testing.assert_array_equal(fun, ref.fun)
    np.testing.assert_array_equal(jac, ref.jac)
