r"""The overdamped end of a motion under a drag that outgrows the spring: a template too.

A drag that is strong at small speed (``c|y'|^α`` below α = 1: its equivalent damping
``g(w)/(2w)`` grows without bound as the speed falls) ends the motion by an overdamped
arc: from a turning point ``a`` the mass does not cross the centre but creeps to it,
the drag balancing the spring, ``g(|y'|) ≈ y``. The polar half cycle of
:mod:`bayestribo.model.laws._core` cannot follow it (the drag turns θ back before
y' = 0: ``D = 1 - cos θ g/r <= 0``); this module integrates it to rest.

The half cycle's polar steps are taken up to the last node before a step where D falls
below :data:`_D_SWITCH` (:func:`polar_checkpoint`: those steps are as accurate as any
half cycle's), and from there the motion is integrated with the position as the clock
(:func:`overdamped_end`): y falls monotonically to 0 on an overdamped arc (y' = -w,
w' = y - g(w) > 0 at w = 0, so w stays positive while y does), and with
``s = ln(y_s/y)``

.. math::

    \frac{dw}{ds} = \frac{y (y - g(w))}{w},\qquad
    \frac{dτ}{ds} = \frac{y}{w},\qquad
    \frac{dC}{ds} = \frac{y E}{w},\quad E = \tfrac12 (y^2 + w^2).

The first equation is stiff along the creep (its rate ``y g'(w)/w`` grows without
bound as y falls), so it is taken by the L-stable singly diagonally implicit
Runge-Kutta method SDIRK4 of Hairer and Wanner (order 4, an embedded order 3 for the
step size; a scalar Newton solve per stage) [1]_. Once the motion follows the
quasi-static balance ``g(w₀(y)) = y`` closely enough, the rest of ∫E is the balance's,
:func:`creep_integral`, whose relative error is the relative departure of w from
w₀ at most: the sum ends where that error is below :data:`_CREEP_TOLERANCE` of the
integral so far. Where the rest diverges (a power drag at α <= 1/3: the creep never
ends, and its ∫E is infinite) or the arc crosses the centre after all, the row stays
outside the law's domain (NaN), as an overdamped arc was before. Given an end
(a record's end, or its detected stop: ``creep_end`` of
:meth:`bayestribo.model.laws.Law.pi_grid`), the arc is integrated up to it instead, C
there returned, and the rest never taken: finite at every α.

Like ``_core_shared`` this text is written after :mod:`._core`'s into one generated
module (:func:`bayestribo.model.laws.integrator._law_source`), where ``drag``,
``rates_at``, ``interpolate``, ``_GL_X`` and ``_GL_W`` are defined; it has no
``from __future__ import annotations`` for that reason.

References
----------
.. [1] E. Hairer and G. Wanner, *Solving Ordinary Differential Equations II: Stiff and
   Differential-Algebraic Problems*, 2nd ed., Springer (1996), Sec. IV.6, Table 6.5.
"""

import math
from typing import TYPE_CHECKING

import numba
import numpy as np
from numpy.typing import NDArray

from bayestribo.model.laws._core_shared import _FAST

if TYPE_CHECKING:  # defined by the template this text follows, and for each law
    from bayestribo.model.laws._core import (
        _GL_W,
        _GL_X,
        _OFFSETS,
        _TABLES,
        LADDER,
        interpolate,
        nodes,
        rates_at,
    )

    def drag(w: float, c: NDArray) -> float: ...


# The polar steps are kept up to the last node before one whose stages have D below
# this: the angle still advances at half its undamped rate, and the steps are as
# accurate as a half cycle's.
_D_SWITCH = 0.5
# The rest of ∫E is taken from the quasi-static balance once the error it may carry
# (the relative departure of w from the balance's, times that rest) is below this
# fraction of the integral so far: the half cycles' own tolerance past the record.
_CREEP_TOLERANCE = 1e-12
# Relative tolerance of the steps on w and on the arc's ∫E.
_ARC_RTOL = 1e-6
# At most this many steps of the arc (a creep that never settles on the balance
# leaves the row outside the law's domain).
_ARC_MAX_STEPS = 4000
# SDIRK4 (Hairer and Wanner, Table 6.5): γ = 1/4, stiffly accurate, its last row b;
# b_hat the embedded third-order weights.
_SD_A = np.array(
    [
        [0.25, 0.0, 0.0, 0.0, 0.0],
        [0.5, 0.25, 0.0, 0.0, 0.0],
        [17.0 / 50.0, -1.0 / 25.0, 0.25, 0.0, 0.0],
        [371.0 / 1360.0, -137.0 / 2720.0, 15.0 / 544.0, 0.25, 0.0],
        [25.0 / 24.0, -49.0 / 48.0, 125.0 / 16.0, -85.0 / 12.0, 0.25],
    ]
)
_SD_C = np.array([0.25, 0.75, 11.0 / 20.0, 0.5, 1.0])
_SD_E = np.array(
    [
        25.0 / 24.0 - 59.0 / 48.0,
        -49.0 / 48.0 + 17.0 / 96.0,
        125.0 / 16.0 - 225.0 / 32.0,
        0.0,
        0.25,
    ]
)


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def balance_speed(y: float, c: NDArray) -> float:
    """The speed w₀ of the quasi-static balance g(w₀) = y > 0 (bisection within a
    factor 2 found by doubling or halving); inf where the drag cannot balance y."""
    hi = y
    for _ in range(2000):
        if drag(hi, c) >= y:
            break
        hi *= 2.0
    else:
        return math.inf
    lo = 0.5 * hi
    for _ in range(2000):
        if drag(lo, c) < y or lo == 0.0:
            break
        hi = lo
        lo *= 0.5
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if drag(mid, c) < y:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@numba.njit(cache=True, inline="always", error_model="numpy", fastmath=_FAST)
def balance_departure(w0: float, c: NDArray) -> float:
    """ε = 1/g'(w₀)²: the motion's relative departure from the balance's speed w₀ at
    first order, w = w₀ (1 + ε) (its inertia: g(w) = y + w dw/dy)."""
    slope = (drag(1.000001 * w0, c) - drag(0.999999 * w0, c)) / (2e-6 * w0)
    return 1.0 / (slope * slope)


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def _creep_integrand(y: float, c: NDArray) -> float:
    """E/w of the creep at y to first order in its inertia: (y²/2)(1 - ε)/w₀ + w₀/2
    (:func:`balance_departure`); inf where the drag cannot balance y."""
    w0 = balance_speed(y, c)
    if not (w0 > 0.0 and math.isfinite(w0)):
        return math.inf
    return 0.5 * y * y * (1.0 - balance_departure(w0, c)) / w0 + 0.5 * w0


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def creep_integral(a: float, c: NDArray) -> float:
    """∫E dτ of the creep from y = ``a`` > 0 to y = 0 under the drag alone, from its
    quasi-static balance g(w₀) = y corrected to first order in its inertia
    (:func:`_creep_integrand`; the error is of the order of ε² of the integral, ε the
    departure at ``a``): ∫₀^a f(y) dy. Near y = 0, f ∝ y^k (k = 2 - 1/α for a power
    law): the integral diverges for k <= -1 (α <= 1/3: the creep never ends, and its
    energy integral is infinite; NaN then), and is taken by Gauss-Legendre in s,
    y = a s^m with m = 3/(k + 1), where the integrand is smooth."""
    k = math.log(_creep_integrand(a * 1e-6, c) / _creep_integrand(a * 1e-7, c)) / math.log(10.0)
    if not k > -0.95:
        return math.nan
    m = min(max(3.0 / (k + 1.0), 3.0), 60.0)
    total = 0.0
    for i in range(_GL_X.size):
        s = 0.5 * (_GL_X[i] + 1.0)
        y = a * s**m
        total += _GL_W[i] * _creep_integrand(y, c) * 0.5 * m * a * s ** (m - 1.0)
    return total


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def polar_checkpoint(
    table: NDArray,
    r0: float,
    c: NDArray,
    steps: int,
    tau_at: NDArray,
    c_at: NDArray,
    e_at: NDArray,
) -> tuple[int, float]:
    """The polar steps of a half cycle under the drag alone (no friction) from
    ``r0``, as :func:`half_cycle` takes them, up to the last node before a step one of
    whose stages has D < :data:`_D_SWITCH`: (k, r) at that node, τ, C and E filled at
    nodes 0 .. k; k = ``steps`` where the half cycle ends without one."""
    h = 1.0 / steps
    r = r0
    tau = 0.0
    cum = 0.0
    tau_at[0] = 0.0
    c_at[0] = 0.0
    g = drag(r * table[0, 0], c)
    e_at[0, 0] = 0.5 * r * r
    e_at[1, 0] = -r * table[0, 0] * g
    for k in range(steps):
        i0 = 2 * k
        a1, b1, e1 = rates_at(table[0, i0], table[1, i0], r, 0.0, g)
        d = table[2, i0]
        d1 = 1.0 - table[1, i0] * g / r
        a1 *= d
        b1 *= d
        e1 *= d
        s1 = table[0, i0 + 1]
        c1 = table[1, i0 + 1]
        d = table[2, i0 + 1]
        ra = r + 0.5 * h * a1
        ga = drag(ra * s1, c)
        a2, b2, e2 = rates_at(s1, c1, ra, 0.0, ga)
        d2 = 1.0 - c1 * ga / ra
        a2 *= d
        b2 *= d
        e2 *= d
        rb = r + 0.5 * h * a2
        gb = drag(rb * s1, c)
        a3, b3, e3 = rates_at(s1, c1, rb, 0.0, gb)
        d3 = 1.0 - c1 * gb / rb
        a3 *= d
        b3 *= d
        e3 *= d
        rc = r + h * a3
        gc = drag(rc * table[0, i0 + 2], c)
        a4, b4, e4 = rates_at(table[0, i0 + 2], table[1, i0 + 2], rc, 0.0, gc)
        d4 = 1.0 - table[1, i0 + 2] * gc / rc
        d = table[2, i0 + 2]
        a4 *= d
        b4 *= d
        e4 *= d
        if not (ra > 0.0 and rb > 0.0 and rc > 0.0):
            return k, r
        if not min(d1, d2, d3, d4) >= _D_SWITCH:
            return k, r
        r += h * (a1 + 2.0 * a2 + 2.0 * a3 + a4) / 6.0
        tau += h * (b1 + 2.0 * b2 + 2.0 * b3 + b4) / 6.0
        cum += h * (e1 + 2.0 * e2 + 2.0 * e3 + e4) / 6.0
        tau_at[k + 1] = tau
        c_at[k + 1] = cum
        sn = table[0, i0 + 2]
        g = drag(r * sn, c)
        e_at[0, k + 1] = 0.5 * r * r
        e_at[1, k + 1] = -r * sn * g
    return steps, r


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def _stage(rhs: float, hg: float, c: NDArray) -> float:
    """The stage speed w > 0 of w (1 + (hγ)²) + hγ g(w) = ``rhs`` (``hg`` = hγ): the
    implicit stage of y' = -w, w' = y - g(w) with y eliminated. Its left side grows
    with w from 0, so the root is bracketed in (0, rhs/(1 + (hγ)²)]: Newton's method,
    bisection where a step leaves the bracket; NaN where ``rhs`` <= 0."""
    if not rhs > 0.0:
        return math.nan
    k = 1.0 + hg * hg
    lo = 0.0
    hi = rhs / k
    x = hi
    for _ in range(100):
        f = x * k + hg * drag(x, c) - rhs
        if f > 0.0:
            hi = x
        else:
            lo = x
        eps = 1e-7 * x
        slope = k + hg * (drag(x + eps, c) - drag(x - eps, c)) / (2.0 * eps)
        nxt = x - f / slope
        if not (lo < nxt < hi):
            nxt = 0.5 * (lo + hi)
        if abs(nxt - x) <= 1e-15 * x:
            return nxt
        x = nxt
    return x


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def overdamped_end(
    theta0: float,
    r0: float,
    c: NDArray,
    tau_at: NDArray,
    c_at: NDArray,
    e_at: NDArray,
    tau: NDArray,
    j: int,
    t_start: float,
    c_start: float,
    tau_end: float,
    out: NDArray,
) -> tuple[float, int, float, float, float]:
    """∫E from the start of an overdamped half cycle (from ``r0`` and θ = ``theta0``
    about the centre, the drag alone) to the end of its motion:
    (∫E, the next grid point, C at ``tau_end``, τ and w where it crosses the centre).
    C = ``c_start`` + ∫₀ E is written into ``out`` at the grid points ``tau[j:]``
    the arc passes (τ from ``t_start``), and C at ``tau_end`` returned where the arc
    passes it (NaN otherwise). ∫E is NaN where the arc cannot be integrated to rest
    (see the module notes). Where the arc crosses the centre after all (a motion
    nearly overdamped, whose polar half cycle failed on a coarse step), ∫E is up to
    the crossing, and τ (from the half cycle's start) and the speed there are
    returned (NaN both otherwise): the half cycle goes on from θ = π/2."""
    n_t = tau.size
    # the polar steps with the ladder's most, whatever the half cycle's own: the arc's
    # accuracy is its own, in every model
    steps = LADDER[-1]
    if theta0 == 0.0:
        table = _TABLES[:, _OFFSETS[-1] : _OFFSETS[-1] + 2 * steps + 1]
    else:
        table = nodes(theta0, steps)
    k, r = polar_checkpoint(table, r0, c, steps, tau_at, c_at, e_at)
    c_end = math.nan
    if k == steps:
        return math.nan, j, c_end, math.nan, math.nan  # no overdamped arc at these steps
    t_chk = tau_at[k]
    while j < n_t and tau[j] < t_start + t_chk:
        out[j] = c_start + interpolate(tau[j] - t_start, k, tau_at, c_at, e_at)
        j += 1
    if tau_end < t_start + t_chk:
        c_end = c_start + interpolate(tau_end - t_start, k, tau_at, c_at, e_at)
    y = r * table[1, 2 * k]
    w = r * table[0, 2 * k]
    if not (y > 0.0 and w >= 0.0):
        return math.nan, j, c_end, math.nan, math.nan
    t = t_chk
    cum = c_at[k]
    scale = c_start + cum
    # the first step: a small part of the arc's time scales (of the undamped motion's
    # from a turning point)
    h = 1e-3 * min(y / w, w / max(abs(y - drag(w, c)), 1e-300)) if w > 0.0 else 1e-4
    ys = np.empty(5)
    ws = np.empty(5)
    rest_bound = 0.0  # the rest from the balance where last computed
    for _ in range(_ARC_MAX_STEPS):
        hg = 0.25 * h
        ok = True
        for i in range(5):
            ry = y
            rw = w
            for m in range(i):
                ry -= h * _SD_A[i, m] * ws[m]
                rw += h * _SD_A[i, m] * (ys[m] - drag(ws[m], c))
            x = _stage(rw + hg * ry, hg, c)
            if not x > 0.0:
                ok = False
                break
            ws[i] = x
            ys[i] = ry - hg * x
        ratio = math.inf
        dc = 0.0
        if ok:
            err_y = 0.0
            err_c = 0.0
            for i in range(5):
                e = 0.5 * (ys[i] * ys[i] + ws[i] * ws[i])
                dc += h * _SD_A[4, i] * e
                err_y += h * _SD_E[i] * ws[i]
                err_c += h * _SD_E[i] * e
            # the error of y and of ∫E: w's own, in the stiff creep, is damped by the
            # drag's pull to the balance (held to it, the steps would stay far below
            # the creep's time scale)
            ratio = max(
                abs(err_y) / (_ARC_RTOL * abs(ys[4])),
                abs(err_c) / (_ARC_RTOL * max(dc, _CREEP_TOLERANCE * scale)),
            )
        if not ratio <= 1.0:
            h *= 0.25 if not math.isfinite(ratio) else max(0.2, 0.9 * ratio**-0.25)
            if h < 1e-14 * max(t, 1.0):
                return math.nan, j, c_end, math.nan, math.nan
            continue
        y_new = ys[4]
        w_new = ws[4]
        t_new = t + h
        e0 = 0.5 * (y * y + w * w)
        e1 = 0.5 * (y_new * y_new + w_new * w_new)
        cross = math.nan
        if not y_new > 0.0:
            # the arc crosses the centre after all (a motion that is nearly
            # overdamped): where, by the cubic Hermite polynomial of y (y' = -w)
            cross = _crossing(t, t_new, y, y_new, -w, -w_new)
        # the grid points and the record's end inside the step (up to the crossing):
        # C by the cubic Hermite polynomial of C and C' = E at its ends
        t_last = t_new if math.isnan(cross) else cross
        while j < n_t and tau[j] < t_start + t_last:
            out[j] = c_start + _hermite3(tau[j] - t_start, t, t_new, cum, cum + dc, e0, e1)
            j += 1
        if tau_end < t_start + t_last and math.isnan(c_end):
            c_end = c_start + _hermite3(tau_end - t_start, t, t_new, cum, cum + dc, e0, e1)
        if not math.isnan(cross):
            # the speed there (w' = y - g(w)) and ∫E up to it: the half cycle goes on
            # from θ = π/2 in the polar steps
            w_cross = _hermite3(cross, t, t_new, w, w_new, y - drag(w, c), y_new - drag(w_new, c))
            c_cross = _hermite3(cross, t, t_new, cum, cum + dc, e0, e1)
            return c_cross, j, c_end, cross, w_cross
        y, w, t, cum = y_new, w_new, t_new, cum + dc
        scale = c_start + cum
        h *= min(4.0, max(0.2, 0.9 * ratio**-0.25)) if ratio > 0.0 else 4.0
        if j < n_t:
            continue  # grid points still ahead
        if math.isfinite(tau_end):
            # a record that ends in the motion: C up to its end is all that counts
            if math.isnan(c_end):
                continue
            return cum, j, c_end, math.nan, math.nan
        # the rest from the balance, once the motion follows it: its error is the
        # motion's departure from the balance's first order, or that order's square
        w0 = balance_speed(y, c)
        first = balance_departure(w0, c)
        departure = max(abs(w / (w0 * (1.0 + first)) - 1.0), first * first)
        if departure > 1e-2:
            continue
        if rest_bound > 0.0 and departure * rest_bound > _CREEP_TOLERANCE * scale:
            continue  # the rest falls as y does: not taken yet
        rest = creep_integral(y, c)
        if not math.isfinite(rest):
            return math.nan, j, c_end, math.nan, math.nan  # a creep that never ends
        if departure * rest <= _CREEP_TOLERANCE * scale:
            return cum + rest, j, c_end, math.nan, math.nan
        rest_bound = rest
    return math.nan, j, c_end, math.nan, math.nan


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def _crossing(t0: float, t1: float, y0: float, y1: float, v0: float, v1: float) -> float:
    """τ in [t0, t1] where the cubic Hermite polynomial of y (y0 > 0 >= y1, slopes v0,
    v1) is 0, by bisection."""
    lo = t0
    hi = t1
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if _hermite3(mid, t0, t1, y0, y1, v0, v1) > 0.0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-15 * hi:
            break
    return 0.5 * (lo + hi)


@numba.njit(cache=True, inline="always", error_model="numpy", fastmath=_FAST)
def _hermite3(x: float, t0: float, t1: float, c0: float, c1: float, e0: float, e1: float) -> float:
    """C at τ = x in [t0, t1] from C and C' = E at both ends (cubic Hermite)."""
    h = t1 - t0
    if h <= 0.0:
        return c0
    s = (x - t0) / h
    s2 = s * s
    s3 = s2 * s
    return (
        (2.0 * s3 - 3.0 * s2 + 1.0) * c0
        + (s3 - 2.0 * s2 + s) * h * e0
        + (-2.0 * s3 + 3.0 * s2) * c1
        + (s3 - s2) * h * e1
    )
