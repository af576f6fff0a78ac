"""Draws kept from a run: at most a fixed number, and the effective sample size they carry.

A run's draws are its steps after burn-in thinned by ⌈τ⌉ (:mod:`bayestribo.inference.sampling`).
A sampler that mixes fast (τ of a few steps) keeps several times the draws its rule
asks for, and everything computed from them afterwards (the pointwise
log-likelihood, the checks, the ΔE(A) bands) costs in proportion. Where
``SamplerSettings.max_draws`` is given, the thinning is coarser so that at most that
many draws are kept (:func:`capped_thin`), and the effective sample size reported is
that of the draws kept (:func:`thinned_ess`), never that of the steps left out.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

__all__ = ["capped_thin", "thinned_ess"]


def capped_thin(steps: int, per_step: int, max_draws: int) -> int:
    """The least thinning that keeps at most ``max_draws`` draws.

    Parameters
    ----------
    steps : int
        Steps after burn-in.
    per_step : int
        Draws per step (walkers × ensembles).
    max_draws : int
        Largest number of draws kept.

    Returns
    -------
    int
        Thinning k >= 1 such that ⌈steps / k⌉ × per_step <= max_draws where any k can
        (one step's draws at least).
    """
    kept_steps = max(1, max_draws // max(per_step, 1))
    return max(1, math.ceil(max(steps, 1) / kept_steps))


def thinned_ess(draws: int, tau: NDArray, thin: int) -> NDArray:
    """Effective sample size of ``draws`` draws taken every ``thin`` steps of chains of
    integrated autocorrelation time τ.

    The autocorrelation of the thinned chain is taken to fall as an autoregressive
    chain's of the same τ: ρ(t) = r^t with r = (τ − 1)/(τ + 1), so the thinned chain's
    τ_k = (1 + r^k)/(1 − r^k) and its effective sample size draws/τ_k (draws/τ for
    k = 1; about draws/1.3 at k = τ, the draws for k of several τ).

    Parameters
    ----------
    draws : int
        Draws kept (all walkers and ensembles).
    tau : ndarray
        τ per parameter [steps], at least 1.
    thin : int
        Steps between kept draws.

    Returns
    -------
    ndarray
        Effective sample size per parameter.
    """
    tau = np.maximum(np.asarray(tau, dtype=float), 1.0)
    r_k = ((tau - 1.0) / (tau + 1.0)) ** int(thin)
    return draws * (1.0 - r_k) / (1.0 + r_k)
