"""The optimiser's residual rows in one compiled call (fused_residuals.py) against the
Python rows of ``start.refine``.

The compiled rows must be the Python rows to the bit, so that the least squares and
the optimum they find are unchanged: checked at the points the least squares ask for
and at points beyond a bound of the support, outside it, with a Gaussian prior, for
every posterior variant the compiled density serves; the Python rows are used where
the compiled form does not serve a point.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from _sim import simulate_flat

from bayestribo.inference import build_posterior, start
from bayestribo.inference.posterior import Posterior
from bayestribo.inference.priors import Normal, Uniform
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.increments import pi_data
from bayestribo.signal.noise import noise_model


@pytest.fixture(scope="module")
def data():
    run = simulate_flat(
        seed=5,
        zeta=0.0236,
        mu_k=0.0294,
        displacement_noise_m=1.5e-6,
        velocity_noise_m_per_s=1.5e-7,
        sample_rate_Hz=5000.0,
        offset_m=1e-4,
    )
    decay = energy_decay(run.time, run.displacement, run.velocity, rig=run.rig())
    return pi_data(decay, noise_model(decay, run.metadata), seed=0)


VARIANTS = {
    "exact": {},
    "averaged": {"model": "averaged"},
    "discrepancy": {"discrepancy": True},
    "shape": {"discrepancy": True, "fixed": {"log10_discrepancy": -3.0}},
    "fixed ratio": {"fixed": {"mu_s_ratio": 1.2}},
    "no friction": {"friction": False},
    "gaussian y0": {"priors": {"y0": Normal(1.0, 0.5)}},
    "bounded y0": {"priors": {"y0": Uniform(0.0, 1.0)}},
}


def _point(post: Posterior) -> np.ndarray:
    """A point of high density (the record's truth, ratio and discrepancy in range)."""
    centre = {
        "zeta": 0.0236,
        "mu_k": 0.0294 * 0.5,
        "mu_s_ratio": 1.2,
        "y0": post.likelihood.data.y0,
        "log10_discrepancy": -3.0,
        "log10_shape": -3.0,
    }
    return np.array([centre[n] for n in post.names])


def _rows_asked(post: Posterior, theta: np.ndarray, monkeypatch, compiled: bool):
    """The rows the least squares of ``refine`` receive at their own points and at
    points far off (beyond the bounds of ζ and μ_k, out of the support), and the
    result of ``refine``, with the compiled rows or without."""
    if not compiled:
        monkeypatch.setattr(Posterior, "residual_rows", property(lambda self: None))
    asked: list[np.ndarray] = []
    real = start._least_squares

    def spy(fun, jac, n, method):
        solution = real(fun, jac, n, method)
        rng = np.random.default_rng(0)
        for scale in (1e-2, 1.0, 1e2, 1e4):
            u = scale * rng.standard_normal(n)
            asked.append(fun(u))
            asked.append(jac(u))
        asked.append(fun(np.full(n, -1e6)))  # beyond every lower bound
        return solution

    monkeypatch.setattr(start, "_least_squares", spy)
    result = start.refine(post, theta)
    monkeypatch.undo()
    return asked, result


@pytest.mark.parametrize("variant", list(VARIANTS))
def test_compiled_rows_are_the_python_rows_to_the_bit(data, variant, monkeypatch):
    post = build_posterior(data, **VARIANTS[variant])
    assert post.residual_rows is not None
    theta = _point(post)
    if variant == "bounded y0":
        theta[post.names.index("y0")] = 0.5
    assert np.isfinite(post(theta[None])[0])
    rows, (opt, cov) = _rows_asked(post, theta, monkeypatch, compiled=True)
    ref_rows, (ref_opt, ref_cov) = _rows_asked(post, theta, monkeypatch, compiled=False)
    assert len(rows) == len(ref_rows) == 9
    for got, ref in zip(rows, ref_rows, strict=True):
        np.testing.assert_array_equal(got, ref)
    np.testing.assert_array_equal(opt, ref_opt)
    np.testing.assert_array_equal(cov, ref_cov)
    # the far points: rows out of the support (1e6) and steps beyond bounds
    assert np.any(rows[-1] == 1e6)
    assert np.any(np.abs(rows[-1]) > 0) and np.all(np.isfinite(rows[-1]))


def test_a_point_the_compiled_form_does_not_cover_is_left_to_python(data):
    # the averaged model with ζ allowed below 0: the compiled density flags ζ < 0
    # (outside the model's domain), where the reference raises its error
    # ζ's prior below 0, outside the law's support: build_posterior refuses it, the
    # Posterior itself takes it
    post = build_posterior(data, model="averaged")
    post = dataclasses.replace(post, priors=post.priors.replace(zeta=Uniform(-0.1, 0.3)))
    theta = _point(post)
    at = np.arange(len(theta), dtype=np.int64)[:2]
    scale = np.array([1e-3, 1e-3])
    none = np.empty(0, dtype=np.int64)
    args = (theta, at, theta[:2], scale, np.full(2, -np.inf), np.full(2, np.inf), none)
    gauss = (none, np.empty(0), np.empty(0))
    size = post.residual_size
    inside = post.residual_rows(np.zeros((1, 2)), *args, *gauss, size)
    assert inside is not None and np.all(np.isfinite(inside))
    below = np.array([[-0.03 / 1e-3 - theta[0] / 1e-3, 0.0]])  # ζ = -0.03
    assert post.residual_rows(below, *args, *gauss, size) is None


def test_without_a_compiled_density_there_are_no_compiled_rows(data):
    post = build_posterior(data)
    assert Posterior(post.priors, post.likelihood, compiled=False).residual_rows is None
