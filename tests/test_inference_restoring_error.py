"""A measured restoring force's error marginalised into the draws (Eq. 1 of
:mod:`bayestribo.inference.restoring_error`).

Known target: a Gaussian conditional posterior p(θ | β) = N(m₀ + J (β - β₀), Σ), whose
mixture over β ~ N(β₀, se²) is N(m₀, Σ + se² J Jᵀ) exactly. The cross-derivative of its
log density gives J back, and the shifted draws have the mixture's covariance.
"""

from __future__ import annotations

import numpy as np
import pytest

from bayestribo.inference.restoring_error import (
    RestoringError,
    _cross_derivative,
    _draws_in_support,
    shifted,
)

M0 = np.array([0.005, 0.002, 0.01])
SIGMA = np.array(
    [
        [4.0e-10, -1.0e-10, 2.0e-10],
        [-1.0e-10, 1.0e-10, -0.5e-10],
        [2.0e-10, -0.5e-10, 9.0e-10],
    ]
)
J = np.array([-0.02, 0.01, 0.05])
BETA0, SE = 0.033, 0.004


class _Gaussian:
    """log p(θ | β) of the known target, rows (n, d) -> (n,)."""

    def __init__(self, beta: float) -> None:
        self.mean = M0 + J * (beta - BETA0)
        self.precision = np.linalg.inv(SIGMA)

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        d = np.atleast_2d(theta) - self.mean
        return -0.5 * np.einsum("ni,ij,nj->n", d, self.precision, d)


class _Priors:
    """Uniform priors on [0, 1] per coordinate."""

    def logpdf(self, theta: np.ndarray) -> np.ndarray:
        inside = np.all((theta >= 0.0) & (theta <= 1.0), axis=1)
        return np.where(inside, 0.0, -np.inf)


NAMES = ("zeta", "mu_k", "c2")


class _Posterior:
    priors = _Priors()
    names = NAMES


@pytest.mark.parametrize("where", [0.0, 1.5])
def test_the_cross_derivative_gives_the_shift_of_a_gaussian(where):
    # at the mean and away from it (the derivative of a Gaussian's score is constant)
    center = M0 + where * np.sqrt(np.diag(SIGMA))
    c = _cross_derivative(
        _Gaussian(BETA0 - SE), _Gaussian(BETA0 + SE), center, 0.25 * np.sqrt(np.diag(SIGMA)), SE
    )
    assert SIGMA @ c == pytest.approx(J, rel=1e-6)


def test_the_shifted_draws_have_the_mixtures_covariance():
    rng = np.random.default_rng(3)
    flat = rng.multivariate_normal(M0, SIGMA, 200_000)
    eps, unshifted = _draws_in_support(_Posterior(), flat, J, SE, rng)
    assert unshifted == 0
    error = RestoringError("beta", BETA0, SE, dict(zip(NAMES, J, strict=True)), {}, eps, 0)
    draws = shifted(flat, error)
    expected = SIGMA + SE**2 * np.outer(J, J)
    sd = np.sqrt(np.diag(expected))
    # 200 000 draws: the sample sds within 1 % (their relative se is 0.16 %)
    assert np.sqrt(np.diag(np.cov(draws, rowvar=False))) == pytest.approx(sd, rel=0.01)
    assert draws.mean(axis=0) == pytest.approx(M0, abs=0.01 * sd.min())


def test_a_shift_out_of_the_support_is_drawn_again_or_kept():
    rng = np.random.default_rng(4)
    # draws at the support's edge: half of the shifts leave it, and are drawn again
    flat = np.tile([0.0, 0.5, 0.5], (1000, 1))
    jac = np.array([1.0, 0.0, 0.0])
    eps, unshifted = _draws_in_support(_Posterior(), flat, jac, SE, rng)
    assert unshifted == 0 and np.all(eps >= 0.0)
    # a shift that leaves it whatever ε is kept at ε = 0, and counted
    flat = np.tile([0.0, 1.0, 0.5], (10, 1))
    eps, unshifted = _draws_in_support(_Posterior(), flat, np.array([1.0, 1.0, 0.0]), SE, rng)
    assert unshifted == 10 and np.all(eps == 0.0)
