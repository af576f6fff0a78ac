"""R-hat: the rank-normalised split Gelman-Rubin diagnostic over independent chains.

Numpy alone, ArviZ's values to the last bit (Vehtari et al. 2021), so that a fit does
not import ArviZ. The sampler's stopping rule (:mod:`bayestribo.inference.sampling`),
the mode check's dropped transients (:mod:`bayestribo.inference.modes`) and the
importance correction (:mod:`bayestribo.inference.correction`) all use it.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

__all__ = ["rhat"]


def rhat(chains: NDArray) -> NDArray:
    """Rank-normalised split R-hat per parameter over independent chains.

    The diagnostic of Vehtari et al. (2021), as :func:`arviz.rhat` computes it (the
    default ``method="rank"``), in numpy alone, so that a fit does not import ArviZ:
    each chain is split in halves; the draws are replaced by the normal quantiles of
    their pooled ranks (ties averaged, Blom's offset 3/8), once as they are (bulk)
    and once folded about their median (tail); R-hat is the larger of the two
    Gelman-Rubin ratios. The variances are summed in order, as ArviZ's compiled
    variance does, so the values are ArviZ's to the last bit.

    Parameters
    ----------
    chains : ndarray
        Shape (chains, draws, params).

    Returns
    -------
    ndarray
        R-hat per parameter; NaN where a parameter has a NaN draw, or with fewer
        than 2 chains or 4 draws.

    References
    ----------
    A. Vehtari, A. Gelman, D. Simpson, B. Carpenter and P.-C. Bürkner (2021),
    Rank-normalization, folding, and localization: an improved R-hat for assessing
    convergence of MCMC, *Bayesian Analysis* 16(2), 667-718.
    """
    chains = np.asarray(chains, dtype=float)
    return np.array([_rank_rhat(chains[..., i]) for i in range(chains.shape[-1])])


def _rank_rhat(ary: NDArray) -> float:
    """Rank-normalised split R-hat of one parameter's draws, shape (chains, draws)."""
    n_chain, n_draw = ary.shape
    if np.isnan(ary).any() or n_chain < 2 or n_draw < 4:
        return math.nan
    half = n_draw // 2
    split = np.vstack((ary[:, :half], ary[:, n_draw - half :]))
    bulk = _gelman_rubin(_z_scale(split))
    tail = _gelman_rubin(_z_scale(np.abs(split - np.median(split))))
    return max(bulk, tail)


def _z_scale(ary: NDArray) -> NDArray:
    """Normal quantiles of the pooled average ranks, Blom's offset c = 3/8."""
    from scipy.special import ndtri

    c = 3 / 8
    return ndtri((_average_ranks(ary) - c) / (ary.size - 2 * c + 1)).reshape(ary.shape)


def _average_ranks(ary: NDArray) -> NDArray:
    """Ranks 1..n of the flattened values, ties given their average rank (as
    ``scipy.stats.rankdata(method="average")``)."""
    flat = ary.reshape(-1)
    order = np.argsort(flat, kind="mergesort")
    ordered = flat[order]
    first = np.concatenate(([True], ordered[1:] != ordered[:-1]))
    dense = np.cumsum(first)
    bounds = np.concatenate((np.flatnonzero(first), [flat.size]))
    ranks = np.empty(flat.size)
    ranks[order] = 0.5 * (bounds[dense] + bounds[dense - 1] + 1)
    return ranks


def _sequential_var(ary: NDArray) -> NDArray:
    """Sample variance (ddof 1) along the last axis from sums taken in order, as
    ArviZ's compiled ``stats_variance_1d`` does (not numpy's pairwise sum)."""
    n = ary.shape[-1]
    total = np.cumsum(ary, axis=-1)[..., -1]
    squares = np.cumsum(ary * ary, axis=-1)[..., -1]
    mean = total / n
    return (squares / n - mean * mean) * (n / (n - 1))


def _gelman_rubin(ary: NDArray) -> float:
    """The R-hat ratio of chains (rows) of equal length."""
    n = ary.shape[1]
    between = n * _sequential_var(np.mean(ary, axis=1))
    within = np.mean(_sequential_var(ary))
    return float(np.sqrt((between / within + n - 1) / n))
