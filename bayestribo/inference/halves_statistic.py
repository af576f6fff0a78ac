r"""The halves' test statistic from posterior draws, with its Monte Carlo error carried.

Each half's posterior gives ΔE(A)/k at the swings compared as draws: their mean m and
standard deviation s estimate the posterior's, from n draws of effective size n_e
(the chains' effective sample size over their draws, at most one per draw). The
difference of two halves' posterior means is compared with its spread,

.. math::  z_j = (\hat m_1 - \hat m_2) / \sqrt{\hat s_1^2 (1 + 1/n_1) + \hat s_2^2 (1 + 1/n_2)},

in which the terms ``s²/n`` are the Monte Carlo variance of each estimated mean
(independent draws of two independent fits): a few hundred draws give the test the
level the exact posterior means would, where leaving them out would make it
anti-conservative by ``1/n``. The Bonferroni p-value over the n swings,
``min(1, 2 n Φ(-max|z_j|))``, is that of :mod:`bayestribo.inference.halves`.

What is not carried in ``z`` is the Monte Carlo error of the estimated sds, a relative
``√((κ - 1)/(4 n))`` for draws of kurtosis κ (``1/√(2n)`` for normal ones), which
moves ``z`` by that fraction of itself. :func:`verdict_is_clear` uses it to decide
whether fewer draws already settle the verdict: when every swing's ``|z_j|`` is
:data:`CLEAR_SDS` of these Monte Carlo standard deviations (of the mean's part and the
sd's part together) below the threshold, or one swing's is as far above it, more
draws would give the same verdict (a chance of about 3e-5 per swing that they would
not, in the normal approximation); otherwise more draws are needed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.stats
from numpy.typing import NDArray

__all__ = [
    "CLEAR_SDS",
    "SwingDifference",
    "swing_difference",
    "threshold",
    "verdict_is_clear",
    "weighted_moments",
]

#: Monte Carlo standard deviations of z by which a verdict from fewer draws must clear
#: the threshold to be kept.
CLEAR_SDS = 4.0


@dataclass(frozen=True)
class SwingDifference:
    """The halves' difference at each swing, from their draws.

    Attributes
    ----------
    z : ndarray
        Difference of the means over its sd, the Monte Carlo error of the means
        carried, per swing.
    z_mc_sd : ndarray
        Monte Carlo standard deviation of ``z`` (the means' and the sds' error), per
        swing.
    largest : float
        The largest ``|z|``.
    p_value : float
        Its Bonferroni p-value over the swings.
    """

    z: NDArray
    z_mc_sd: NDArray
    largest: float
    p_value: float


def weighted_moments(
    d: NDArray, weights: NDArray | None = None
) -> tuple[NDArray, NDArray, NDArray]:
    """Mean, variance and kurtosis (not excess; 3 where not defined) of each column of
    the draws ``d`` (draws, swings) under ``weights`` (draws,), non-negative (None:
    equal). The variance is made unbiased with Kish's effective number of the weights
    (with equal weights, the sample variance with ``ddof=1``)."""
    w = np.ones(d.shape[0]) if weights is None else np.asarray(weights, dtype=float)
    w = w / w.sum()
    kish = 1.0 / float(np.sum(w * w))
    mean = w @ d
    centred = d - mean
    second = w @ centred**2
    with np.errstate(invalid="ignore", divide="ignore"):
        kurtosis = (w @ centred**4) / second**2
    return mean, second * kish / (kish - 1.0), np.where(np.isfinite(kurtosis), kurtosis, 3.0)


def swing_difference(
    first: NDArray,
    second: NDArray,
    first_draws: float,
    second_draws: float,
    weights: tuple[NDArray | None, NDArray | None] = (None, None),
) -> SwingDifference:
    """z at each swing from the halves' draws of ΔE(A) (module notes).

    Parameters
    ----------
    first, second : ndarray
        Draws of ΔE(A)/k [length unit²] of each half, shape (draws, swings), finite.
    first_draws, second_draws : float
        Effective number of each half's draws, at least 2 (with weights, at most their
        Kish number).
    weights : tuple of ndarray or None
        Importance weights of each half's draws, (draws,), non-negative (None: equal):
        draws of a surrogate posterior weighted to the exact one.

    Returns
    -------
    SwingDifference

    Raises
    ------
    ValueError
        Draws not two-dimensional with the same number of swings, fewer than two of
        them, weights not one finite non-negative value per draw with a positive sum,
        or an effective number below 2.
    """
    d1, d2 = np.asarray(first, dtype=float), np.asarray(second, dtype=float)
    if d1.ndim != 2 or d2.ndim != 2 or d1.shape[1] != d2.shape[1]:
        raise ValueError(
            f"first, second: expected (draws, swings) arrays with as many swings, got "
            f"shapes {d1.shape} and {d2.shape}"
        )
    if min(d1.shape[0], d2.shape[0]) < 2:
        raise ValueError(
            f"first, second: expected two draws or more, got {d1.shape[0]}, {d2.shape[0]}"
        )
    if not (first_draws >= 2 and second_draws >= 2):
        raise ValueError(
            f"first_draws, second_draws: expected at least 2, got {first_draws}, {second_draws}"
        )
    for name, d, w in (("first", d1, weights[0]), ("second", d2, weights[1])):
        if w is None:
            continue
        w = np.asarray(w, dtype=float)
        if w.shape != (d.shape[0],) or not (np.all(np.isfinite(w)) and np.all(w >= 0)):
            raise ValueError(
                f"weights: expected {d.shape[0]} finite non-negative values for the "
                f"{name} half's draws, got shape {w.shape}"
            )
        if not w.sum() > 0:
            raise ValueError(f"weights: expected a positive sum for the {name} half's draws")
    n1, n2 = float(first_draws), float(second_draws)
    m1, var1, k1 = weighted_moments(d1, weights[0])
    m2, var2, k2 = weighted_moments(d2, weights[1])
    mc = var1 / n1 + var2 / n2
    total = var1 + var2 + mc
    with np.errstate(invalid="ignore", divide="ignore"):
        z = (m1 - m2) / np.sqrt(total)
        # the sd's relative error, each half's weighted by its share of the variance
        sd_rel = (
            np.sqrt(
                ((var1 / total) ** 2 * (k1 - 1.0) / n1) + ((var2 / total) ** 2 * (k2 - 1.0) / n2)
            )
            / 2.0
        )
        z_mc_sd = np.sqrt(mc / total + (z * sd_rel) ** 2)
    ok = np.isfinite(z)
    z = np.where(ok, z, 0.0)
    z_mc_sd = np.where(ok & np.isfinite(z_mc_sd), z_mc_sd, 0.0)
    largest = float(np.max(np.abs(z))) if z.size else 0.0
    p = float(min(1.0, 2.0 * z.size * scipy.stats.norm.sf(largest))) if z.size else 1.0
    return SwingDifference(z, z_mc_sd, largest, p)


def threshold(n_swings: int, p: float) -> float:
    """The ``|z|`` at which the Bonferroni p-value over ``n_swings`` swings is ``p``."""
    return float(scipy.stats.norm.isf(p / (2.0 * n_swings)))


def verdict_is_clear(difference: SwingDifference, p: float) -> bool:
    """Whether more draws would give the same verdict at the level ``p``: every swing
    :data:`CLEAR_SDS` Monte Carlo sds of z below the threshold, or one as far above."""
    z, mc = np.abs(difference.z), difference.z_mc_sd
    limit = threshold(z.size, p)
    return bool(np.any(z - CLEAR_SDS * mc > limit) or np.all(z + CLEAR_SDS * mc < limit))
