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

__all__ = ["CLEAR_SDS", "SwingDifference", "swing_difference", "threshold", "verdict_is_clear"]

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


def _kurtosis(d: NDArray) -> NDArray:
    """Kurtosis (not excess) of each column of ``d``; 3 where it is not defined."""
    centred = d - d.mean(axis=0)
    var = np.mean(centred**2, axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        k = np.mean(centred**4, axis=0) / var**2
    return np.where(np.isfinite(k), k, 3.0)


def swing_difference(
    first: NDArray, second: NDArray, first_draws: float, second_draws: float
) -> SwingDifference:
    """z at each swing from the halves' draws of ΔE(A) (module notes).

    Parameters
    ----------
    first, second : ndarray
        Draws of ΔE(A)/k [length unit²] of each half, shape (draws, swings), finite.
    first_draws, second_draws : float
        Effective number of each half's draws, at least 2.

    Returns
    -------
    SwingDifference

    Raises
    ------
    ValueError
        Draws not two-dimensional with the same number of swings, fewer than two of
        them, or an effective number below 2.
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
    n1, n2 = float(first_draws), float(second_draws)
    var1, var2 = d1.var(axis=0, ddof=1), d2.var(axis=0, ddof=1)
    mc = var1 / n1 + var2 / n2
    total = var1 + var2 + mc
    with np.errstate(invalid="ignore", divide="ignore"):
        z = (d1.mean(axis=0) - d2.mean(axis=0)) / np.sqrt(total)
        # the sd's relative error, each half's weighted by its share of the variance
        sd_rel = (
            np.sqrt(
                ((var1 / total) ** 2 * (_kurtosis(d1) - 1.0) / n1)
                + ((var2 / total) ** 2 * (_kurtosis(d2) - 1.0) / n2)
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
