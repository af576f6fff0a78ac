r"""The correlation of the increments of a record whose displacement is integrated.

A displacement integrated from a velocity (a velocity-only record, or an
accelerometer's record integrated twice) holds the velocity's noise integrated: a
low-frequency error that reaches every increment of a stretch of the record alike. It
enters the increments of E = ½(y² + y'²) through ``y w``, w the integrated noise, and
an accelerometer's velocity noise, itself a random walk held at the rests, through
``y' η``: over a half cycle y and y' change sign, so the increments' errors alternate
about a slowly varying level. Neighbouring increments are then correlated (-0.4 at
lag 1 on a dry-friction accelerometer record, -0.2 on a velocity alone at 10 samples
a period), and farther ones too: independent increments leave ζ's and μ_k's intervals
1.4-1.8 times too wide on the accelerometer record (measured against 3000 draws of its
noise).

:func:`integrated_noise` takes the covariance of the increments from the Monte Carlo
draws of their noise (:func:`bayestribo.signal.increments.increment_draws`), the
likelihood whitens the increments with it
(:mod:`bayestribo.inference.likelihood`). A covariance S estimated from n draws of m
increments has an inverse biased up, ``E[S⁻¹] = (n - 1)/(n - m - 2) Σ⁻¹`` (the inverse
Wishart's mean): the precision the likelihood takes would be that much too large and
the intervals too narrow, so S is scaled by that factor; the draws number at least
:data:`DRAWS_PER_INCREMENT` per increment, which keeps it below 1.12 and the weights'
own noise small (on the dry-friction record, ζ's sd from the whitened increments
within 10 % of that from the covariance of 3000 draws).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["DRAWS_PER_INCREMENT", "correlation_matrix", "integrated_noise", "replicates_for"]

#: Monte Carlo draws per increment for the covariance of an integrated record's
#: increments (at least the draws asked for).
DRAWS_PER_INCREMENT = 10


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
        ``max(n_replicates, DRAWS_PER_INCREMENT · m)``.
    """
    if n_increments < 1:
        raise ValueError(f"n_increments: expected at least 1, got {n_increments}")
    return max(int(n_replicates), DRAWS_PER_INCREMENT * int(n_increments))


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
