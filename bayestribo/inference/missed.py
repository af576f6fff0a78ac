"""A run whose walkers missed a part of the posterior that holds higher density.

An ensemble sampler explores the part of the posterior its walkers start in. Where
the posterior is split (a law whose Π is not defined on thin bands of its parameters,
as a power-law drag below α = 1 was before its creep to rest was integrated:
:mod:`bayestribo.model.laws._creep`), the walkers can stay in one part, mix there, and
pass every convergence check, while another part holds density far above theirs.
Points evaluated under the exact posterior elsewhere in the fit (the draws of a
quadratic surrogate checked against it, :func:`bayestribo.inference.surrogate.check`)
show it: one whose log density exceeds every draw of the run by more than
:data:`MARGIN` lies in a part the walkers did not reach, and the run's draws are not
the posterior's. :func:`missed_reason` says so, and the run is reported not converged.
A checked draw is where a surrogate's posterior put it, not the top of the part it
fell in: :func:`climbed` adds the exact least squares' optimum from the best of them
(HarmOsc3 under ``power``, seed 1: the best checked draw 21 500 nats below the
walkers' best, its optimum 3 900 above).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from bayestribo.inference.posterior import Posterior

__all__ = ["MARGIN", "climbed", "missed_reason"]

#: Log density [nats] by which a point must exceed the run's best draw to be taken as
#: a part of the posterior the walkers missed. The best kept draw of a run of 1000
#: effective draws is within a few nats of the mode of the part it explored, in any
#: number of parameters a law has; a part higher by this much would hold e^10 times
#: the mass of as wide a neighbourhood of that mode.
MARGIN = 10.0


def climbed(posterior: Posterior, points: Sequence[NDArray]) -> list[NDArray]:
    """``points`` and the optimum of ``posterior`` found by the exact least squares
    (:func:`bayestribo.inference.start.refine`) from the point of highest density
    among them (none added where no point has a finite density, or where the least
    squares fail)."""
    from bayestribo.inference.start import refine

    rows = [np.asarray(p, dtype=float) for p in points if p is not None]
    if not rows:
        return rows
    lp = np.asarray(posterior(np.vstack(rows)), dtype=float)
    if not np.isfinite(lp).any():
        return rows
    best = rows[int(np.nanargmax(np.where(np.isfinite(lp), lp, -np.inf)))]
    try:
        top, _ = refine(posterior, best)
    except (ValueError, ArithmeticError):
        # a check of the run, not the fit: a least squares that fails leaves the points
        return rows
    return [*rows, np.asarray(top, dtype=float)]


def missed_reason(
    log_posterior: Callable[[NDArray], NDArray],
    names: Sequence[str],
    run_log_prob: NDArray,
    points: Sequence[NDArray],
    margin: float = MARGIN,
) -> str | None:
    """Why a run's draws are not the posterior's, if a point elsewhere holds more.

    Parameters
    ----------
    log_posterior : callable
        The log posterior density the run sampled, rows (n, d) -> (n,), in the
        coordinates of ``names`` and of ``points``.
    names : sequence of str
        The coordinates' names (d).
    run_log_prob : ndarray
        The log posterior of each of the run's draws (any shape).
    points : sequence of ndarray
        Points (d,) found elsewhere (e.g. the best checked draw of each quadratic
        surrogate); none: nothing is said.
    margin : float
        Nats by which the best point must exceed the best draw (:data:`MARGIN`).

    Returns
    -------
    str or None
        The reason, naming the point and by how much it is higher; None when no point
        exceeds the run's best draw by ``margin`` (or the run holds no finite
        density).
    """
    rows = [np.asarray(p, dtype=float) for p in points if p is not None]
    drawn = np.asarray(run_log_prob, dtype=float)
    if not rows or not np.isfinite(drawn).any():
        return None
    at = np.vstack(rows)
    lp = np.asarray(log_posterior(at), dtype=float)
    if not np.isfinite(lp).any():
        return None
    k = int(np.nanargmax(np.where(np.isfinite(lp), lp, -np.inf)))
    gap = float(lp[k] - np.nanmax(drawn))
    if not gap > margin:
        return None
    where = ", ".join(f"{n} = {v:.6g}" for n, v in zip(names, at[k], strict=True))
    return (
        f"the posterior is higher by {gap:.4g} in log density at {where} (found from the "
        "draws of a quadratic surrogate checked against it) than at any draw of the "
        "run: the walkers stayed in one part of a posterior split in parts (as by rows "
        "the law cannot compute: a drag's creep to rest beyond the integrator's "
        "accuracy), and the draws are that part's, not the posterior's"
    )
