r"""The correlation of the increments of an accelerometer's record.

An accelerometer's velocity is the integral of its acceleration, its drift taken off
between the rests: its noise is a random walk held at the rests and free between
them, and the displacement integrated from that velocity holds the walk integrated.
Both are low-frequency errors that reach every increment of a stretch of the record
alike. They enter the increments of E = ½(y² + y'²) through ``y' η`` and ``y w`` (η,
w the velocity's and the displacement's noise): over a half cycle y and y' change
sign, so the increments' errors alternate about a slowly varying level. Measured over
96 independent records of a dry-friction rig (``tests/test_signal_increment_correlation.py``'s),
the correlation of neighbouring increments is -0.63 (the Monte Carlo below: -0.65),
+0.27 at lag 2 (+0.29) and -0.23 at lag 4 (-0.22): a run of four increments has 0.4
times the sum of their variances, and independent increments leave ζ's and μ_k's
intervals too wide (``benchmarks/acceleration.py``: z sd 0.35-0.55).

:func:`integrated_noise` takes the covariance of the increments from the Monte Carlo
draws of their noise (:func:`bayestribo.signal.increments.increment_draws`), and the
likelihood whitens the increments with it (:mod:`bayestribo.inference.likelihood`).
A covariance S estimated from n draws of m increments has an inverse biased up,
``E[S⁻¹] = (n - 1)/(n - m - 2) Σ⁻¹`` (the inverse Wishart's mean): the precision the
likelihood takes would be that much too large and the intervals too narrow, so S is
scaled by that factor; the draws number at least :data:`DRAWS_PER_INCREMENT` per
increment (up to :data:`MAX_DRAWS`), which keeps it below 1.12 up to 90 increments
and the weights' own noise small (on a benchmark dry-friction record, ζ's sd from
increments whitened with 300 draws within 10 % of that from the covariance of 3000
draws; 40 draws an increment instead of 10 changed the whitened errors' statistics by
less than their sampling error).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "DRAWS_PER_INCREMENT",
    "MAX_DRAWS",
    "correlation_matrix",
    "integrated_noise",
    "replicates_for",
]

#: Monte Carlo draws per increment for the covariance of an integrated record's
#: increments (at least the draws asked for), and at most this many draws: a
#: quadratic-drag record of 139 increments would take 1390, each an integration of
#: the sensor's noise over 5535 samples (1000: the inverse's bias factor 1.16).
DRAWS_PER_INCREMENT, MAX_DRAWS = 10, 1000


def replicates_for(n_increments: int, n_replicates: int) -> int:
    """Draws of the Monte Carlo that estimates the covariance of ``n_increments``.

    Parameters
    ----------
    n_increments : int
        m, the increments.
    n_replicates : int
        The draws asked for.

    Returns
    -------
    int
        ``max(n_replicates, min(DRAWS_PER_INCREMENT · m, MAX_DRAWS))``, and more than
        m + 2 (:func:`integrated_noise`).
    """
    if n_increments < 1:
        raise ValueError(f"n_increments: expected at least 1, got {n_increments}")
    wanted = min(DRAWS_PER_INCREMENT * int(n_increments), MAX_DRAWS)
    return max(int(n_replicates), wanted, int(n_increments) + 3 + int(n_increments) // 4)


def integrated_noise(draws: NDArray) -> tuple[NDArray, NDArray]:
    """The noise bias and the covariance of the increments from their Monte Carlo draws.

    Parameters
    ----------
    draws : ndarray
        Shape (n, m): the change of each of m increments in each of n draws of the
        noise (dimensionless, units of Π), n > m + 2.

    Returns
    -------
    bias : ndarray
        Shape (m,): the mean change.
    covariance : ndarray
        Shape (m, m): the sample covariance times (n - 1)/(n - m - 2), whose inverse
        is unbiased (see the module notes).
    """
    draws = np.asarray(draws, dtype=float)
    if draws.ndim != 2:
        raise ValueError(f"draws: expected shape (n, m), got {draws.shape}")
    n, m = draws.shape
    if n <= m + 2:
        raise ValueError(f"draws: expected more than m + 2 = {m + 2} draws, got {n}")
    bias = draws.mean(axis=0)
    centred = draws - bias
    covariance = (centred.T @ centred) / (n - m - 2)
    return bias, covariance


def correlation_matrix(covariance: NDArray, variance: NDArray) -> NDArray:
    """The correlation of the increments whose noise has ``covariance`` and, added to it
    independently per increment, as much more as makes ``variance``.

    The increments' final variances hold independent terms besides the integrated
    noise (a floor from the rest's noise, the end of motion's location), added on the
    diagonal.

    Parameters
    ----------
    covariance : ndarray
        Shape (m, m).
    variance : ndarray
        Shape (m,): the final variances, at least the diagonal of ``covariance``.

    Returns
    -------
    ndarray
        Shape (m, m), ones on the diagonal.
    """
    covariance = np.asarray(covariance, dtype=float)
    variance = np.asarray(variance, dtype=float)
    diagonal = np.diag(covariance)
    if variance.shape != diagonal.shape or np.any(variance < diagonal * (1 - 1e-12)):
        raise ValueError("variance: expected one value per increment, at least the covariance's")
    scale = 1.0 / np.sqrt(variance)
    out = covariance * scale[:, None] * scale[None, :]
    np.fill_diagonal(out, 1.0)
    return out
