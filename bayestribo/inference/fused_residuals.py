r"""The optimiser's residual rows in one compiled call (numba).

The least squares of the start stage (:func:`bayestribo.inference.start.refine`)
evaluate the standardized residuals a few hundred times per fit, one to five points
at a time. Each evaluation in Python is two dozen array operations around the
compiled residuals (:meth:`~bayestribo.inference.fused.FusedLogPosterior.standardized_residuals`):
the points from the optimiser's scaled step, a step across a bound of the priors'
support moved onto the bound with a residual for the excess, the prior's support
tested, the Gaussian priors' residuals, the rows that cannot be evaluated set to
1e6; microseconds each where the arithmetic of a row takes about two.
:func:`residual_rows` does all of it in one compiled call, with the same operations
in the same order (the rows are the same to the bit: tests), so that the optimiser
and its optimum are unchanged.

It serves a posterior with a compiled density of a law with a closed form; the rows
of a call with a point the compiled form does not cover (outside the averaged
model's domain, a singular nuisance system) are left to the Python evaluation, which
gives the reference's answer.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.fused import (
    _BASE,
    FusedLogPosterior,
    _log_prior,
    _model_pi,
    _standardized_row,
)

__all__ = ["residual_rows"]

#: The files whose compiled functions :func:`_rows` calls, and a digest of each
#: (see :data:`bayestribo.inference.fused.DEPENDS_ON`).
DEPENDS_ON = {
    "bayestribo/inference/fused.py": "ef7d9216c45d427a",
}

#: The residual of a point that cannot be evaluated (as :func:`bayestribo.inference.start.refine`).
_FAR = 1e6


@numba.njit(cache=True, error_model="numpy")
def _rows(
    u: NDArray,
    theta: NDArray,
    at: NDArray,
    start: NDArray,
    scale: NDArray,
    low: NDArray,
    high: NDArray,
    bounded: NDArray,
    gauss_at: NDArray,
    gauss_mu: NDArray,
    gauss_sigma: NDArray,
    size: int,
    prior: NDArray,
    columns: NDArray,
    fixed: NDArray,
    data: NDArray,
    scalars: NDArray,
    out: NDArray,
) -> bool:
    """The rows of :func:`residual_rows` into ``out``; False (``out`` partly set) where
    a point inside the priors' support is outside the compiled form's domain."""
    k, n_free = u.shape
    n_gauss = gauss_at.size
    m = data.shape[1]
    q = size - m
    th = np.empty(theta.size)
    part = np.empty(n_free)
    pi = np.empty(m)
    var = np.empty(m)
    a = np.empty((q, q))
    b = np.empty(q)
    x = np.empty(q)
    prec = np.empty(q)
    xw = np.empty((q, m))
    resid = np.empty(size)
    for r in range(k):
        for c in range(out.shape[1]):
            out[r, c] = _FAR
        for j in range(n_free):
            part[j] = start[j] + u[r, j] * scale[j]
        if bounded.size:
            for i in range(bounded.size):
                j = bounded[i]
                inside = part[j]
                if inside < low[j]:
                    inside = low[j]
                if inside > high[j]:
                    inside = high[j]
                out[r, size + n_gauss + i] = (part[j] - inside) / scale[j]
            for i in range(bounded.size):
                j = bounded[i]
                if part[j] < low[j]:
                    part[j] = low[j]
                if part[j] > high[j]:
                    part[j] = high[j]
        for i in range(theta.size):
            th[i] = theta[i]
        for j in range(n_free):
            th[at[j]] = part[j]
        if not math.isfinite(_log_prior(th, prior)):
            continue
        if not _model_pi(th, columns, fixed, data, scalars, pi):
            return False
        if not _standardized_row(
            th, pi, columns, fixed, data, scalars, var, a, b, x, prec, xw, resid
        ):
            return False
        finite = True
        for c in range(size):
            if not math.isfinite(resid[c]):
                finite = False
        if not finite:
            continue
        for c in range(size):
            out[r, c] = resid[c]
        for i in range(n_gauss):
            out[r, size + i] = (th[gauss_at[i]] - gauss_mu[i]) / gauss_sigma[i]
    return True


def residual_rows(
    fused: FusedLogPosterior,
    u: NDArray,
    theta: NDArray,
    at: NDArray,
    start: NDArray,
    scale: NDArray,
    low: NDArray,
    high: NDArray,
    bounded: NDArray,
    gauss_at: NDArray,
    gauss_mu: NDArray,
    gauss_sigma: NDArray,
    size: int,
) -> NDArray | None:
    """The least squares' residuals at the scaled steps ``u``, as
    :func:`bayestribo.inference.start.refine` computes them, in one compiled call.

    Parameters
    ----------
    fused : FusedLogPosterior
        The compiled density's tables.
    u : ndarray
        Scaled steps of the free coordinates, (k, f): the points are
        ``start + u·scale`` in the free coordinates ``at`` of ``theta``.
    theta : ndarray
        The point whose held coordinates the rows keep, (d,), sampling coordinates.
    at : ndarray
        Columns of the free coordinates in ``theta`` (f,), int64.
    start, scale : ndarray
        The free coordinates where the least squares began and their steps (f,).
    low, high : ndarray
        The priors' support of the free coordinates (f,), infinite where unbounded.
    bounded : ndarray
        The free coordinates with a finite bound (int64): a step beyond one is
        evaluated on the bound, with a residual for the excess in units of its step.
    gauss_at, gauss_mu, gauss_sigma : ndarray
        Columns of ``theta`` with a Gaussian prior, its mean and sd: the residuals
        (θ − μ)/σ.
    size : int
        The standardized residuals and the nuisances' (m + q).

    Returns
    -------
    ndarray or None
        (k, size + Gaussian priors + bounded coordinates): the standardized residuals
        with the nuisances', the Gaussian priors' and the bounds' excess; 1e6 in the
        first two parts of a row outside the priors' support or with a residual that
        is not finite. None where the compiled form does not serve the posterior (a
        law without a closed form, residuals of another size) or a point of the call
        (the caller evaluates it in Python).
    """
    if fused.law is not None or size != fused.data.shape[1] + _BASE + int(fused.scalars[6]):
        return None
    out = np.empty((u.shape[0], size + gauss_at.size + bounded.size))
    ok = _rows(
        np.ascontiguousarray(u, dtype=np.float64),
        np.ascontiguousarray(theta, dtype=np.float64),
        at,
        start,
        scale,
        low,
        high,
        bounded,
        gauss_at,
        gauss_mu,
        gauss_sigma,
        int(size),
        fused.prior,
        fused.columns,
        fused.fixed,
        fused.data,
        fused.scalars,
        out,
    )
    return out if ok else None
