"""Compiled kernel of the exact Π for the sampler's hot path (numba).

The same closed forms as :mod:`bayestribo.model.exact`, written for one parameter set
and one τ at a time, compiled with numba: a sampler evaluates a few walkers at a few
dozen τ per call, where numpy's per-call overhead (about a hundred array operations of
a few microseconds each) outweighs the arithmetic. The numpy implementation stays the
reference; the tests require the two to agree to 1e-12 relative.

No argument checks here: the caller (the likelihood, whose priors keep the parameters
in range) is responsible for 0 <= ζ < 1, μ_k >= 0 and μ_s >= μ_k.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

__all__ = ["exact_pi_grid", "exact_pi_rows"]

_TINY = 1e-100
_SERIES_XL = 1e-6
_GMINUS_SERIES = 1e-3
#: Below this (upper - 1)·x the decay of the half cycles left is taken from e^{-(upper-1)x}
#: (relative error at most this many ε from its argument's rounding).
_TOP_ARGUMENT = 30.0
#: From this n·x on the whole half cycles' sums divide by their constants through
#: reciprocals (below it e1 - e2 cancels by 1/(n·x) and the divisions are kept).
_RECIPROCAL_NX = 0.1


@numba.njit(cache=True, inline="always")
def _gminus(z: float) -> float:
    if z < _GMINUS_SERIES:
        return z * z * (0.5 - z * (1.0 / 6.0 - z * (1.0 / 24.0 - z * (1.0 / 120.0 - z / 720.0))))
    return math.expm1(-z) + z


@numba.njit(cache=True, inline="always")
def _geometric(n: float, x: float) -> float:
    if x < _TINY:
        return n
    return math.expm1(-x * n) / math.expm1(-x)


@numba.njit(cache=True, inline="always")
def _expm1_ratio(a: float, length: float) -> float:
    if abs(a) < _TINY:
        return length
    return -math.expm1(-a * length) / a


@numba.njit(cache=True, inline="always")
def _amplitude(n: float, a0: float, mu_k: float, x: float) -> float:
    return a0 * math.exp(-n * x) - 2.0 * mu_k * _geometric(n, x)


@numba.njit(cache=True, inline="always")
def _amplitude_of(n: float, a0: float, mu_k: float, x: float, omq: float) -> tuple[float, float]:
    """:func:`_amplitude` with one transcendental call, for the loop over the grid:
    e^{-nx} where e^{-nx} - 1 does not cancel, e^{-nx} - 1 where it would (1 + that is
    then at least 0.6, exact enough); ``omq`` = 1 - e^{-x}. Returns the amplitude and
    e^{-nx}."""
    if x < _TINY:
        return a0 - 2.0 * mu_k * n, 1.0
    nx = n * x
    if nx > 0.5:
        e = math.exp(-nx)
        em = e - 1.0
    else:
        em = math.expm1(-nx)
        e = 1.0 + em
    return a0 * e + 2.0 * mu_k * (em * (1.0 / omq)), e


@numba.njit(cache=True, inline="always")
def _whole(
    n: float,
    amp: float,
    mu_k: float,
    x: float,
    q: float,
    half: float,
    f1: float,
    f2: float,
    omq: float,
    g_x: float,
    em_nx: float = math.nan,
) -> float:
    """Σ ∫E over n whole half cycles starting with amplitude amp (see exact.py);
    ``em_nx`` is e^{-nx} - 1 where the caller has it (NaN: computed here)."""
    if n <= 0.0:
        return 0.0
    if x < _TINY:
        d1 = n
        d2 = n
        e1 = 0.5 * n * (n - 1.0)
        e2 = e1
        e3 = (n - 1.0) * n * (2.0 * n - 1.0) / 6.0
    else:
        nx = n * x
        em = math.expm1(-nx) if math.isnan(em_nx) else em_nx
        g_nx = _gminus(nx) if nx < _GMINUS_SERIES else em + nx
        if nx >= _RECIPROCAL_NX:
            # products with the reciprocals of the grid's constants: e1 - e2 cancels
            # by about a factor nx only, so their last-bit differences from the
            # divisions below stay in the last bits
            inv_omq = 1.0 / omq
            inv_1pq = 1.0 / (1.0 + q)
            d1 = -em * inv_omq
            d2 = d1 * (2.0 + em) * inv_1pq
            e1 = (g_nx - n * g_x) * (inv_omq * inv_omq)
            e2 = d1 * (d1 - 1.0) * inv_1pq
            e3 = (e1 - e2) * inv_omq
        else:
            d1 = -em / omq
            d2 = d1 * (2.0 + em) / (1.0 + q)
            e1 = (g_nx - n * g_x) / (omq * omq)
            e2 = d1 * (d1 - 1.0) / (1.0 + q)
            if nx < _SERIES_XL:
                s2 = (n - 1.0) * n * (2.0 * n - 1.0) / 6.0
                s3 = (0.5 * n * (n - 1.0)) ** 2
                e3 = s2 - x * (s3 - s2)
            else:
                e3 = (e1 - e2) / omq
    sum_a = amp * d1 - 2.0 * mu_k * e1
    sum_a2 = amp * amp * d2 - 4.0 * mu_k * amp * e2 + 4.0 * mu_k * mu_k * e3
    return 0.5 * mu_k * mu_k * half * n + mu_k * f1 * sum_a + 0.5 * f2 * sum_a2


@numba.njit(cache=True, inline="always")
def _partial(
    s: float, amp: float, mu_k: float, z: float, om: float, be: float, q: float, half: float
) -> float:
    """∫E from local time s to the end of a half cycle of amplitude amp."""
    decay = math.exp(-z * s)
    t = math.tan(0.5 * om * s)
    inv = 1.0 / (1.0 + t * t)
    sin = 2.0 * t * inv
    cos = (1.0 - t * t) * inv
    p1 = 2.0 * z * q + decay * (2.0 * z * (cos + be * sin) - sin * (1.0 / om))
    sin2 = 2.0 * sin * cos
    cos2 = cos * cos - sin * sin
    g_s = 0.5 * z * decay * decay * ((be * be - 1.0) * cos2 - 2.0 * be * sin2)
    g_end = 0.5 * z * q * q * (be * be - 1.0)
    a = 2.0 * z
    ratio = half - s if abs(a) < _TINY else -math.expm1(-a * (half - s)) * (1.0 / a)
    p2 = (1.0 + be * be) * decay * decay * ratio + g_end - g_s
    return 0.5 * mu_k * mu_k * (half - s) + mu_k * amp * p1 + 0.5 * amp * amp * p2


@numba.njit(cache=True)
def _one(
    tau: NDArray,
    y0: float,
    z: float,
    mk: float,
    ms: float,
    yp0: float,
    tau_end: float,
    out: NDArray,
) -> None:
    omega = math.sqrt((1.0 - z) * (1.0 + z))
    be = z / omega
    x = math.pi * be
    q = math.exp(-x)
    half = math.pi / omega
    omq = -math.expm1(-x)
    g_x = _gminus(x)
    f1 = 2.0 * z * (1.0 + q)
    f2 = (1.0 + be * be) * _expm1_ratio(2.0 * z, half) + 0.5 * z * (be * be - 1.0) * (q * q - 1.0)
    # start: a turning point, or a virtual one σ₀ before a moving state
    if yp0 == 0.0:
        sigma0 = 0.0
        a0 = abs(y0) - mk
        n_min = 0.0
    else:
        sv = 1.0 if yp0 > 0.0 else -1.0
        r = y0 + mk * sv + z * yp0
        sigma0 = math.atan2(omega * abs(yp0), -sv * r) / omega
        a0 = math.hypot(omega * yp0, r) * math.exp(z * sigma0)
        n_min = 1.0
    # number of moving half cycles
    delta = ms - mk
    excess = a0 - delta
    never = mk == 0.0 and excess > 0.0 and (x < _TINY or delta == 0.0)
    if never:
        m = math.inf
    elif excess <= 0.0:
        m = n_min
    else:
        if mk == 0.0:
            # w = excess/A₀ and excess/den = w/(1 - q), exactly: a tiny amplitude times
            # a tiny 1 - q (den below the smallest double) is not 0/0
            w = excess / a0
            per_den = w / omq
        else:
            den = a0 * omq + 2.0 * mk
            w = excess * omq / den
            per_den = excess / den
        lr = 1.0 if w < _TINY else -math.log1p(-w) / w
        n_star = per_den * _expm1_ratio(x, 1.0) * lr
        m = max(n_min, np.ceil(n_star))  # a float: n_star may be huge or infinite
        if math.isfinite(m):
            if m - 1.0 >= n_min and _amplitude(m - 1.0, a0, mk, x) <= delta:
                m -= 1.0
            if _amplitude(m, a0, mk, x) > delta:
                m += 1.0
    tau_stop = m * half - sigma0
    end = min(tau_stop, tau_end)
    # truncation at tau_end inside the motion
    upper = m
    tail = 0.0
    if tau_end < tau_stop:
        n_e = np.floor((tau_end + sigma0) / half)
        s_e = tau_end + sigma0 - n_e * half
        upper = n_e + 1.0
        tail = _partial(s_e, _amplitude(n_e, a0, mk, x), mk, z, omega, be, q, half)
    endless = 0.5 * f2 / -math.expm1(-2.0 * x) if x >= _TINY else math.inf
    # A half cycle's amplitude and the integral over the half cycles after it depend on
    # its index alone: computed once per half cycle, not once per time (a grid holds
    # several times in each), with the same operations, so the values are the same.
    # The whole half cycles after the n-th, upper - n - 1 of them, decay by
    # e^{-(upper-1)x}/e^{-nx}: one division instead of an exponential where that is
    # at most e^{-0.5} (its difference from 1 does not cancel) and e^{-(upper-1)x}
    # carries the rounding of an argument below _TOP_ARGUMENT only.
    top_arg = (upper - 1.0) * x
    top_ok = x >= _TINY and top_arg < _TOP_ARGUMENT
    top = math.exp(-top_arg) if top_ok else 0.0
    last_n = math.nan
    amp = 0.0
    rest = 0.0
    for i in range(tau.size):
        t = tau[i]
        if t >= end:
            out[i] = 0.0
            continue
        n = np.floor((t + sigma0) / half)
        s = t + sigma0 - n * half
        if n != last_n:
            last_n = n
            amp, e_n = _amplitude_of(n, a0, mk, x, omq)
            amp_next = q * amp - 2.0 * mk
            length = upper - n - 1.0
            if math.isinf(length):
                rest = endless * amp_next * amp_next
            else:
                em_length = top / e_n - 1.0 if top_ok and length * x > 0.5 else math.nan
                rest = _whole(
                    max(length, 0.0), amp_next, mk, x, q, half, f1, f2, omq, g_x, em_length
                )
        head = _partial(s, amp, mk, z, omega, be, q, half)
        out[i] = head + rest - tail


@numba.njit(cache=True)
def _grid(
    tau: NDArray, y0: NDArray, z: NDArray, mk: NDArray, ms: NDArray, yp0: float, tau_end: float
) -> NDArray:
    out = np.empty((y0.size, tau.size))
    for p in range(y0.size):
        _one(tau, y0[p], z[p], mk[p], ms[p], yp0, tau_end, out[p])
    return out


def exact_pi_grid(
    tau: NDArray,
    y0: NDArray,
    zeta: NDArray,
    mu_k: NDArray,
    mu_s: NDArray,
    yp0: float = 0.0,
    tau_end: float | None = None,
) -> NDArray:
    """Exact Π at sorted ``tau`` for parameter vectors of one length P: shape (P, T).

    Same result as :func:`bayestribo.model.exact_pi` with parameters of shape (P, 1),
    without its argument checks (see the module notes).
    """
    flat = [np.ascontiguousarray(np.ravel(a), dtype=np.float64) for a in (y0, zeta, mu_k, mu_s)]
    end = math.inf if tau_end is None else float(tau_end)
    return _grid(np.ascontiguousarray(tau, dtype=np.float64), *flat, float(yp0), end)


@numba.njit(cache=True)
def _rows(
    tau: NDArray, y0: NDArray, z: NDArray, mk: NDArray, ms: NDArray, yp0: NDArray, end: NDArray
) -> NDArray:
    out = np.empty(tau.shape)
    for p in range(y0.size):
        _one(tau[p], y0[p], z[p], mk[p], ms[p], yp0[p], end[p], out[p])
    return out


def exact_pi_rows(
    tau: NDArray,
    y0: NDArray,
    zeta: NDArray,
    mu_k: NDArray,
    mu_s: NDArray,
    yp0: NDArray,
    tau_end: NDArray,
) -> NDArray:
    """Exact Π of any broadcast of its arguments, in the compiled kernel.

    Every argument is broadcast to one shape; where the parameters are constant along
    its last axis (the usual ``(P, 1)`` parameters against ``(T,)`` times), each row
    is one trajectory evaluated at its T times, otherwise every element is its own
    trajectory. ``tau_end`` is ``inf`` for "to the end of motion". No argument checks
    (see the module notes).
    """
    arrays = np.broadcast_arrays(
        *(np.asarray(a, dtype=np.float64) for a in (tau, y0, zeta, mu_k, mu_s, yp0, tau_end))
    )
    shape = arrays[0].shape
    params = arrays[1:]
    if len(shape) >= 1 and all(a.strides[-1] == 0 for a in params):
        # copies: numba reads a broadcast view's writeable flag with a FutureWarning
        rows = [np.array(a[..., 0], order="C").reshape(-1) for a in params]
        times = np.array(arrays[0], order="C").reshape(-1, shape[-1] if shape[-1] else 1)
    else:
        rows = [np.array(a, order="C").reshape(-1) for a in params]
        times = np.array(arrays[0], order="C").reshape(-1, 1)
    if times.size == 0:
        return np.zeros(shape)
    return _rows(times, *rows).reshape(shape)
