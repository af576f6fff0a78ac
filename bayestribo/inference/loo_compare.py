"""PSIS-LOO's result for one law, and the laws compared by it, without ArviZ.

ArviZ takes two to three seconds to import (with xarray and pandas); a command-line
``--law auto`` spent a third of its time on it, for three of its functions. They are
written out here, each to ArviZ's values (``tests/test_inference_loo.py`` checks them
against ArviZ 0.x, to rounding):

* :func:`ess_mean`: the effective sample size of the mean of one quantity's chains,
  as ``arviz.ess(..., method="mean")`` computes it (split chains, autocovariance by
  FFT, Geyer's initial monotone sequence; Vehtari et al. 2021), the relative
  efficiency of PSIS-LOO's draws;
* :class:`LooResult`: what ``arviz.loo(..., pointwise=True)`` returns, as a mapping of
  the same keys (``elpd_loo``, ``se``, ``p_loo``, ``loo_i``, ``pareto_k``, ...);
* :func:`compare`: ``arviz.compare(..., ic="loo")`` of such results, its default
  stacking weights (Yao et al. 2018) from the same constrained optimisation, as rows
  of plain numbers, best first.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import NDArray

__all__ = ["LooResult", "compare", "ess_mean"]


def ess_mean(ary: NDArray) -> float:
    """Effective sample size of the mean of draws (chains, draws), as
    ``arviz.ess(ary, method="mean")``: NaN with fewer than 4 draws or a NaN draw; the
    number of draws where they are all equal.

    Parameters
    ----------
    ary : ndarray
        Draws of one quantity, shape (chains, draws).

    Returns
    -------
    float
        The effective number of draws.
    """
    ary = np.atleast_2d(np.asarray(ary, dtype=float))
    if ary.shape[1] < 4 or np.isnan(ary).any():
        return math.nan
    half = ary.shape[1] // 2
    return _ess(np.vstack((ary[:, :half], ary[:, -half:])))


def _ess(ary: NDArray) -> float:
    """ArviZ's ``_ess`` of split chains (rows)."""
    if np.max(ary) - np.min(ary) < np.finfo(float).resolution:
        return float(ary.size)
    n_chain, n_draw = ary.shape
    acov = _autocov(ary)
    chain_mean = ary.mean(axis=1)
    mean_var = np.mean(acov[:, 0]) * n_draw / (n_draw - 1.0)
    var_plus = mean_var * (n_draw - 1.0) / n_draw
    if n_chain > 1:
        var_plus += _sequential_var(chain_mean)
    rho = np.zeros(n_draw)
    rho_even = 1.0
    rho[0] = rho_even
    rho_odd = 1.0 - (mean_var - np.mean(acov[:, 1])) / var_plus
    rho[1] = rho_odd
    # Geyer's initial positive sequence
    t = 1
    while t < (n_draw - 3) and (rho_even + rho_odd) > 0.0:
        rho_even = 1.0 - (mean_var - np.mean(acov[:, t + 1])) / var_plus
        rho_odd = 1.0 - (mean_var - np.mean(acov[:, t + 2])) / var_plus
        if (rho_even + rho_odd) >= 0:
            rho[t + 1] = rho_even
            rho[t + 2] = rho_odd
        t += 2
    max_t = t - 2
    if rho_even > 0:
        rho[max_t + 1] = rho_even
    # Geyer's initial monotone sequence
    t = 1
    while t <= max_t - 2:
        if (rho[t + 1] + rho[t + 2]) > (rho[t - 1] + rho[t]):
            rho[t + 1] = (rho[t - 1] + rho[t]) / 2.0
            rho[t + 2] = rho[t + 1]
        t += 2
    ess = n_chain * n_draw
    tau = -1.0 + 2.0 * np.sum(rho[: max_t + 1]) + np.sum(rho[max_t + 1 : max_t + 2])
    tau = max(tau, 1 / np.log10(ess))
    return math.nan if np.isnan(rho).any() else float(ess / tau)


def _autocov(ary: NDArray) -> NDArray:
    """Autocovariance of each row at every lag, by FFT (ArviZ's ``autocov``)."""
    from scipy.fft import next_fast_len

    n = ary.shape[1]
    m = next_fast_len(2 * n)
    centred = ary - ary.mean(axis=1, keepdims=True)
    spectrum = np.fft.rfft(centred, n=m, axis=1)
    spectrum *= np.conjugate(spectrum)
    return np.fft.irfft(spectrum, n=m, axis=1)[:, :n] / n


def _sequential_var(x: NDArray) -> float:
    """Sample variance (ddof 1) from sums taken in order, as ArviZ's compiled
    variance (not numpy's pairwise sum)."""
    n = x.size
    total = np.cumsum(x)[-1]
    squares = np.cumsum(x * x)[-1]
    mean = total / n
    return float((squares / n - mean * mean) * (n / (n - 1)))


@dataclass(frozen=True)
class LooResult(Mapping):
    """PSIS-LOO of one law, pointwise: the fields of ``arviz.loo(..., pointwise=True)``,
    read by key (``result["elpd_loo"]``) or as attributes.

    Attributes
    ----------
    elpd_loo, se, p_loo : float
        The expected log pointwise predictive density, its standard error and the
        effective number of parameters.
    n_samples, n_data_points : int
        Draws and increments.
    warning : bool
        A Pareto k above ``good_k``.
    loo_i, pareto_k : ndarray
        Each increment's leave-one-out log density and Pareto k, shape (m,).
    scale : str
        "log".
    good_k : float
        The largest reliable k for this many draws.
    """

    elpd_loo: float
    se: float
    p_loo: float
    n_samples: int
    n_data_points: int
    warning: bool
    loo_i: NDArray
    pareto_k: NDArray
    scale: str
    good_k: float

    def __getitem__(self, key: str) -> object:
        if key not in self._keys():
            raise KeyError(key)
        return getattr(self, key)

    def __iter__(self) -> Iterator[str]:
        return iter(self._keys())

    def __len__(self) -> int:
        return len(self._keys())

    @classmethod
    def _keys(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))


#: The largest exponent of the stacking weights' gradient (below exp's overflow).
_MAX_EXPONENT = 700.0

#: The columns of a comparison's rows (:func:`compare`), as ``arviz.compare`` names them.
COLUMNS = ("rank", "elpd_loo", "p_loo", "elpd_diff", "weight", "se", "dse", "warning")


def compare(loos: Mapping[str, LooResult]) -> dict[str, dict[str, float]]:
    """The laws compared by PSIS-LOO, as ``arviz.compare(loos, ic="loo")``.

    Parameters
    ----------
    loos : mapping of str to LooResult
        Each law's PSIS-LOO, pointwise, over the same increments.

    Returns
    -------
    dict
        Law -> its row (:data:`COLUMNS`), best first (highest ``elpd_loo``; ties in
        the order given): ``rank`` (0 for the best), ``elpd_loo``, ``p_loo``,
        ``elpd_diff`` (from the best, ≥ 0) and ``dse`` (its standard error from the
        pointwise differences), ``weight`` (the stacking weights), ``se``,
        ``warning``. One law alone is its own best, its weight 1.

    Raises
    ------
    ValueError
        If the laws' PSIS-LOO are over different numbers of increments.
    """
    from scipy.optimize import Bounds, LinearConstraint, minimize
    from scipy.special import logsumexp

    names = sorted(loos, key=lambda law: -float(loos[law]["elpd_loo"]))
    pointwise = [np.ravel(np.asarray(loos[law]["loo_i"], dtype=float)) for law in names]
    if len({p.size for p in pointwise}) > 1:
        raise ValueError("The number of observations should be the same across all models")
    matrix = np.column_stack(pointwise)
    cols = matrix.shape[1]
    if cols == 1:
        weights = np.ones(1)
    else:
        # ArviZ's score, -Σ_i log Σ_j w_j exp(loo_ij), and its gradient, taken in logs:
        # exp(loo_ij) underflows to 0 for every law of a record that all laws misfit
        # (loo_ij of -1e3 and below), where ArviZ's then takes log 0 and 0/0 (numpy's
        # warnings, and a gradient of NaN)
        def mixture(w: NDArray) -> NDArray:
            # a weight the optimiser steps a rounding below its bound of 0 is 0
            with np.errstate(divide="ignore"):
                return logsumexp(matrix + np.log(np.maximum(w, 0.0)), axis=1)

        def log_score(w: NDArray) -> float:
            return -float(np.sum(mixture(w)))

        def gradient(w: NDArray) -> NDArray:
            # exp(loo_ij - log Σ_k w_k exp(loo_ik)), capped below overflow where the
            # weights leave out the law that holds an increment far better
            cap = _MAX_EXPONENT - math.log(matrix.shape[0])  # the sum stays finite too
            share = np.minimum(matrix - mixture(w)[:, np.newaxis], cap)
            return -np.sum(np.exp(share), axis=0)

        weights = minimize(
            fun=log_score,
            x0=np.full(cols, 1.0 / cols),
            jac=gradient,
            bounds=Bounds(lb=np.zeros(cols), ub=np.ones(cols)),
            constraints=LinearConstraint(np.ones(cols), lb=1.0, ub=1.0),
        )["x"]
    out: dict[str, dict[str, float]] = {}
    for idx, law in enumerate(names):
        diff = pointwise[0] - pointwise[idx]
        out[law] = {
            "rank": float(idx),
            "elpd_loo": float(loos[law]["elpd_loo"]),
            "p_loo": float(loos[law]["p_loo"]),
            "elpd_diff": float(np.sum(diff)),
            "weight": float(weights[idx]),
            "se": float(loos[law]["se"]),
            "dse": float(np.sqrt(len(diff) * np.var(diff))),
            "warning": bool(loos[law]["warning"]),
        }
    return out
