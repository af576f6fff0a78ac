"""Π of every piece of μ_s/μ_k from one integration of the longest motion.

The quadratic surrogate of Π (:mod:`bayestribo.inference.surrogate`) is fitted piecewise
in μ_s/μ_k: between two stop ratios of the motion the pin sticks at the same turning
point, and each piece has its own quadratic in the other coordinates, fitted to the
exact Π at each node (or draw) with a ratio inside that piece. The motions of the
pieces are the same motion, cut at different turning points: the ratio decides only
where the pin sticks (Eq. 8), not how it moves before. So the motion with
μ_s = μ_k (the ratio 1, which runs longest) is integrated once per node, its Π taken
at the grid and at the turning times where the pieces stop, and each piece's Π is

    Π_k(τ_j) = Π(τ_j) - Π(T_k)   for τ_j < T_k,   0 at and after T_k,

``T_k`` the turning time at which a ratio of piece k sticks (the first turning point
whose stop ratio |Y_n|/μ(|Y_n|) it reaches): ``C(T_k) - C(τ_j)`` with ``C = ∫₀^τ E``,
as the integrator's own Π is (:func:`bayestribo.model.laws._core_shared.finish`). One
integration per node instead of one per node and piece (six pieces on the AppStat
HarmOsc2 recording under ``coulomb+power``: 774 integrations of its regressed
surrogate become 129).

The caller checks the pieces at the centre against their direct integration and
integrates every row directly where they differ by more than :data:`TOLERANCE` of
Π(0) (the integrator's own accuracy), or where the longest motion cannot be
integrated (a drag's overdamped arc after a piece's stop).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.likelihood import PiLikelihood

__all__ = ["TOLERANCE", "longest_motion_pi", "piece_rows", "stop_times"]

#: Largest difference from the direct integration, as a fraction of Π(0), at which the
#: pieces' Π from the longest motion are used (the integrator holds Π within ~2e-9 of
#: Π(0); the two differ by rounding where they agree).
TOLERANCE = 1e-9


def stop_times(times: Sequence[NDArray], stops: Sequence[NDArray], ratios: NDArray) -> NDArray:
    """The turning time at which each node's motion sticks at its ratio.

    Parameters
    ----------
    times, stops : sequence of ndarray
        Per node, the turning times and stop ratios of its longest motion (μ_s = μ_k),
        in their order (:func:`bayestribo.inference.surrogate.turning_stops`).
    ratios : ndarray
        μ_s/μ_k at each node, (n,).

    Returns
    -------
    ndarray
        (n,): the time of the first turning point whose stop ratio is at most the
        node's ratio; inf where there is none (the motion outlasts what was listed:
        the record's end, where its Π is the longest motion's).
    """
    out = np.full(len(times), np.inf)
    for i, (t, s) in enumerate(zip(times, stops, strict=True)):
        reached = np.flatnonzero(np.asarray(s) <= ratios[i])
        if reached.size:
            out[i] = float(np.asarray(t)[reached[0]])
    return out


def longest_motion_pi(
    likelihood: PiLikelihood, params: Mapping[str, NDArray], at: NDArray
) -> NDArray:
    """Π of the likelihood's law at the sorted times ``at`` for each row of ``params``
    (the law's parameters and ``y0`` by name, each (n,)), as
    :meth:`~bayestribo.inference.likelihood.PiLikelihood.model_pi` gives it at the
    grid: (n, len(at))."""
    values, y0 = likelihood.law_values(params)
    return likelihood.law_pi(at, values, y0)


def piece_rows(longest: NDArray, at: NDArray, grid: NDArray, stops: NDArray) -> NDArray:
    """Each row's Π at the grid when its motion sticks at ``stops`` (module notes).

    Parameters
    ----------
    longest : ndarray
        (n, len(at)): Π of the longest motion at the times ``at`` (sorted, holding the
        grid and every finite stop time).
    at, grid : ndarray
        The times of ``longest`` and the grid τ_j (m,).
    stops : ndarray
        (n,): each row's stop time (inf: the longest motion's Π).

    Returns
    -------
    ndarray
        (n, m).
    """
    on_grid = np.searchsorted(at, grid)
    out = np.array(longest[:, on_grid], dtype=float)
    finite = np.isfinite(stops)
    if np.any(finite):
        rows = np.flatnonzero(finite)
        base = longest[rows, np.searchsorted(at, stops[rows])]
        cut = np.maximum(out[rows] - base[:, None], 0.0)
        out[rows] = np.where(grid[None, :] < stops[rows, None], cut, 0.0)
    return out
