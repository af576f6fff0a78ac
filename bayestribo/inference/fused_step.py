r"""One grouped sampler step of the single-run fit in one compiled call (numba).

A step of the grouped moves (:mod:`bayestribo.inference.moves`) splits each
ensemble, proposes for one split from the others, evaluates the log posterior of the
proposals and accepts or rejects them, split after split. In Python each split costs
a few dozen array operations and four calls down to the compiled log posterior
(:mod:`bayestribo.inference.fused`), several times the arithmetic. :func:`grouped_step`
runs all splits of a step in one compiled call: the same proposal loops as the moves
(:func:`~bayestribo.inference.moves._de_proposals`,
:func:`~bayestribo.inference.moves._snooker_proposals`), the same log posterior
(:func:`~bayestribo.inference.fused._log_posterior`, its constant parts made once per
step) and the same acceptance rule,
with the random numbers the move drew, so that the chains are bit-identical to the
Python splits' (tests). emcee still runs the chain: its sampler, state, backend and
random state, and the choice of the move at each step.

The step stops before a split whose proposals are not finite or whose log posterior
is NaN or outside the compiled form's domain; the move runs that split and the rest
in Python, where the errors naming the cause are raised.

:func:`independence_step` does the same for a step of the independence move
(:mod:`bayestribo.inference.independence`): the log posterior of every walker's
proposal and the acceptance in one compiled call.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.fused import FusedLogPosterior, _log_posterior_in, _workspace
from bayestribo.inference.moves import DE, _de_proposals, _snooker_proposals

__all__ = ["grouped_step", "independence_step"]

#: The files whose compiled functions :func:`_step` calls, and a digest of each
#: (see :data:`bayestribo.inference.fused.DEPENDS_ON`).
DEPENDS_ON = {
    "bayestribo/inference/fused.py": "ef7d9216c45d427a",
    "bayestribo/inference/moves.py": "3e955db75b8e9506",
}


@numba.njit(cache=True, error_model="numpy")
def _step(
    kind: int,
    coords: NDArray,
    log_prob: NDArray,
    order: NDArray,
    uniform: NDArray,
    gamma: NDArray,
    log_u: NDArray,
    accepted: NDArray,
    prior: NDArray,
    columns: NDArray,
    fixed: NDArray,
    data: NDArray,
    scalars: NDArray,
) -> int:
    """The splits of one step (see :func:`grouped_step`); returns the splits done."""
    nsplits = uniform.shape[0]
    g, per = order.shape
    size = per // nsplits
    ndim = coords.shape[1]
    n = g * size
    out = np.empty(n)
    factors = np.zeros(n)
    # the log posterior's work arrays and the parts the same for every walker, made
    # once for all splits
    pi, var, a, b, x, prec, c, xw, z, norm0 = _workspace(columns, data, scalars)
    for split in range(nsplits):
        if kind == DE:
            q = _de_proposals(coords, order, split, uniform[split], gamma[split])
        else:
            q, metropolis = _snooker_proposals(
                coords, order, split, uniform[split], gamma[split, 0, 0]
            )
            for row in range(n):
                factors[row] = (ndim - 1.0) * metropolis[row]
        for row in range(n):
            for j in range(ndim):
                if not math.isfinite(q[row, j]):
                    return split
        flagged = _log_posterior_in(
            q, prior, columns, fixed, data, scalars, out, pi, var, a, b, x, prec, c, xw, z, norm0
        )
        if flagged > 0:
            return split
        for e in range(g):
            for i in range(size):
                row = e * size + i
                walker = order[e, split * size + i]
                if factors[row] + out[row] - log_prob[walker] > log_u[split, row]:
                    for j in range(ndim):
                        coords[walker, j] = q[row, j]
                    log_prob[walker] = out[row]
                    accepted[walker] = True
    return nsplits


def grouped_step(
    fused: FusedLogPosterior,
    kind: int,
    coords: NDArray,
    log_prob: NDArray,
    order: NDArray,
    uniform: NDArray,
    gamma: NDArray,
    log_u: NDArray,
    accepted: NDArray,
) -> int:
    """One step of a grouped move with the compiled log posterior ``fused``.

    The ``grouped_step`` of :mod:`bayestribo.inference.moves` (see its notes), bound
    to a posterior by :attr:`bayestribo.inference.posterior.Posterior.grouped_step`.

    Parameters
    ----------
    fused : FusedLogPosterior
        The compiled density's tables.
    kind : int
        :data:`~bayestribo.inference.moves.DE` or
        :data:`~bayestribo.inference.moves.SNOOKER`.
    coords : ndarray
        Walkers (G·W, d), C-contiguous float64; updated in place.
    log_prob : ndarray
        Their log posterior (G·W,), float64; updated in place.
    order : ndarray
        Each ensemble's walkers in split order (G, W), int64.
    uniform : ndarray
        The proposals' uniform numbers, (splits, G, W/splits, k).
    gamma : ndarray
        The DE stretches (splits, G, W/splits); the snooker's constant stretch.
    log_u : ndarray
        Log Metropolis uniforms, (splits, G·W/splits).
    accepted : ndarray
        Bool (G·W,); set True for every walker that moved.

    Returns
    -------
    int
        Splits completed (all of them unless one could not be evaluated here; none
        for a law without a closed form, whose Π comes from its own compiled
        integrator through Python: the move runs its splits; all of them for the
        quadratic surrogate of such a law's Π, :mod:`bayestribo.inference.surrogate`,
        which is compiled with the closed forms).
    """
    if fused.law is not None:
        return 0
    return int(
        _step(
            kind,
            coords,
            log_prob,
            order,
            uniform,
            gamma,
            log_u,
            accepted,
            fused.prior,
            fused.columns,
            fused.fixed,
            fused.data,
            fused.scalars,
        )
    )


@numba.njit(cache=True, error_model="numpy")
def _independence(
    coords: NDArray,
    log_prob: NDArray,
    q: NDArray,
    factors: NDArray,
    log_u: NDArray,
    accepted: NDArray,
    prior: NDArray,
    columns: NDArray,
    fixed: NDArray,
    data: NDArray,
    scalars: NDArray,
) -> bool:
    """One independence step (see :func:`independence_step`); False, nothing
    changed, where a proposal is not finite or its log posterior cannot be given."""
    n, ndim = q.shape
    for row in range(n):
        for j in range(ndim):
            if not math.isfinite(q[row, j]):
                return False
    out = np.empty(n)
    pi, var, a, b, x, prec, c, xw, z, norm0 = _workspace(columns, data, scalars)
    flagged = _log_posterior_in(
        q, prior, columns, fixed, data, scalars, out, pi, var, a, b, x, prec, c, xw, z, norm0
    )
    if flagged > 0:
        return False
    for row in range(n):
        if factors[row] + out[row] - log_prob[row] > log_u[row]:
            for j in range(ndim):
                coords[row, j] = q[row, j]
            log_prob[row] = out[row]
            accepted[row] = True
    return True


def independence_step(
    fused: FusedLogPosterior,
    coords: NDArray,
    log_prob: NDArray,
    q: NDArray,
    factors: NDArray,
    log_u: NDArray,
    accepted: NDArray,
) -> bool:
    """One step of the independence move with the compiled log posterior ``fused``.

    The ``independence_step`` of :mod:`bayestribo.inference.independence` (see
    :class:`~bayestribo.inference.independence.GroupedIndependenceMove`), bound to a
    posterior by :attr:`bayestribo.inference.posterior.Posterior.independence_step`:
    walker i moves to ``q[i]`` where ``factors[i] + log π(q[i]) − log_prob[i] >
    log_u[i]``, the Metropolis-Hastings rule of the move's Python step.

    Parameters
    ----------
    fused : FusedLogPosterior
        The compiled density's tables.
    coords : ndarray
        Walkers (n, d), C-contiguous float64; updated in place.
    log_prob : ndarray
        Their log posterior (n,), float64; updated in place.
    q : ndarray
        The proposals (n, d).
    factors : ndarray
        log q(x) − log q(y) of each walker (n,).
    log_u : ndarray
        Log Metropolis uniforms (n,).
    accepted : ndarray
        Bool (n,); set True for every walker that moved.

    Returns
    -------
    bool
        True when the step is done; False, nothing changed, where a proposal is not
        finite or its log posterior cannot be given here (the move then runs the step
        in Python, where the errors are raised), and for a law without a closed form.
    """
    if fused.law is not None:
        return False
    return bool(
        _independence(
            coords,
            log_prob,
            q,
            factors,
            log_u,
            accepted,
            fused.prior,
            fused.columns,
            fused.fixed,
            fused.data,
            fused.scalars,
        )
    )
