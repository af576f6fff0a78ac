"""The part of the two compiled-integrator templates that is the same: a template too.

:mod:`bayestribo.model.laws._core` (the laws on the linear spring, in polar coordinates
about the half cycle's centre) and :mod:`bayestribo.model.laws._restoring_core` (the
laws on a nonlinear restoring force, in τ) integrate a half cycle differently, but
share what a Π row and a swing's drop make of the half cycles: the limits of the sum,
its geometric end past the record, a row outside the law's domain, Π from the energy
integral C, and the secant method on the half cycle of a given swing. They are here,
once. :func:`bayestribo.model.laws.integrator._law_source` writes one template's text,
then this module's, then the law's definitions (``drag``, ``friction``,
``friction_off``, ``HAS_FRICTION``, ``HAS_DRAG``; on a restoring force ``spring`` and
``potential`` too) into one generated module, which numba compiles: these functions
are compiled with the template's, from the same file and into the same cache entries
(inlined where marked ``inline="always"``), and ``swing_ends`` calls the template's own
``half_cycle_end``.

The templates import this module's constants (their decorators and tables read
``_FAST`` when they are imported on their own) and nothing else from it; its
functions are never compiled in this module. It has no ``from __future__ import
annotations``: its text comes after a template's in the generated file, where a
``__future__`` import would be a syntax error (its annotations are evaluated
without it).
"""

import math
from typing import TYPE_CHECKING

import numba
from numpy.typing import NDArray

if TYPE_CHECKING:  # defined by the template this text follows

    def half_cycle_end(a: float, c: NDArray, aux: tuple) -> float: ...


# Floating-point contraction (fused multiply-add) and reciprocals only: no assumption
# of finite values, which the overdamped-arc and end-of-record checks rely on.
_FAST = {"contract", "arcp"}
# Past the record, summing to the end of motion, the sum ends once a half cycle holds
# less than this fraction of it; the rest is extrapolated as a geometric series.
_TAIL_TOLERANCE = 1e-12
# At most this many half cycles are integrated for one parameter set.
_MAX_HALF_CYCLES = 200_000
# At most this many past the record, summing to the end of motion of a record whose
# motion ended: a law whose motion would go on for longer (a friction far too small
# to stop it soon) is far from such a record whatever its tail (the Π it gives at the
# record's end is already the energy of thousands of half cycles, where the record's
# is zero), so its sum stops there instead of at the end of its motion; the optimiser
# and the sampler leave it as they would with its whole tail.
_MAX_PAST_HALF_CYCLES = 20_000


@numba.njit(cache=True, inline="always", error_model="numpy", fastmath=_FAST)
def outside_domain(out: NDArray) -> int:
    """A row outside the law's domain (an overdamped arc, a negative friction): ``out``
    all NaN; the row's status, 1."""
    for i in range(out.size):
        out[i] = math.nan
    return 1


@numba.njit(cache=True, inline="always", error_model="numpy", fastmath=_FAST)
def geometric_rest(last: float, before: float) -> float:
    """The rest of a sum whose last two terms are ``before`` and ``last``, extrapolated
    as a geometric series of ratio ρ = last/before (0 when ρ >= 1 or before <= 0)."""
    rho = last / before if before > 0.0 else 0.0
    if rho < 1.0:
        return last * rho / (1.0 - rho)
    return 0.0


@numba.njit(cache=True, inline="always", error_model="numpy", fastmath=_FAST)
def finish(out: NDArray, tau: NDArray, j: int, c_end: float, total: float, tau_end: float) -> int:
    """Π(τ_i) = C(T) - C(τ_i) into ``out``, which holds C(τ_i) = ∫₀^τ_i E for the ``j``
    grid points passed: T is the end of the record (C there ``c_end``) or, when the
    record outlasts the motion (``c_end`` NaN), its end (C there ``total``). Π is 0 at
    and after T; the row's status, 0."""
    if math.isnan(c_end):
        c_end = total
    for i in range(tau.size):
        if i < j:
            out[i] = max(c_end - out[i], 0.0) if tau[i] < tau_end else 0.0
        else:
            out[i] = 0.0  # at or after the end of motion
    return 0


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def swing_ends(
    target: float, c: NDArray, aux: tuple, guess: float, slope: float
) -> tuple[float, float]:
    """The turning points (a_s, a_e) of the half cycle from rest at a_s whose swing
    ½(a_s + a_e) is ``target`` (static friction ignored), a_e from the template's
    ``half_cycle_end(a_s, c, aux)``; NaN for both where no such half cycle exists.

    The secant method on ½(a_s + a_e(a_s)) = A, to 1e-14 of A, from ``guess`` with
    its first step along ``slope`` ≈ da_s/dA (:func:`swing_guess`, from the swings
    solved before: one half cycle fewer, and the next ones nearer), or where they are
    NaN from the fixed point a_s = A + ½ drop(A) (from 2A where the swing's own start
    does not move)."""
    x0 = guess
    e0 = half_cycle_end(x0, c, aux) if math.isfinite(guess) else math.nan
    if math.isfinite(e0) and math.isfinite(slope):
        f0 = 0.5 * (x0 + e0) - target
        if abs(f0) <= 1e-14 * target:
            return x0, e0
        x1 = x0 - f0 * slope
    else:
        e0 = half_cycle_end(target, c, aux)
        x0 = 2.0 * target if not math.isfinite(e0) else target + 0.5 * (target - e0)
        f0 = 0.5 * (x0 + half_cycle_end(x0, c, aux)) - target
        x1 = x0 - f0
    for _ in range(40):
        end = half_cycle_end(x1, c, aux)
        if not math.isfinite(end):
            break
        f1 = 0.5 * (x1 + end) - target
        if abs(f1) <= 1e-14 * target:
            return x1, end
        if f1 == f0 or not math.isfinite(f0):
            x0, f0 = x1, f1
            x1 = x1 - f1
            continue
        x2 = x1 - f1 * (x1 - x0) / (f1 - f0)
        x0, f0 = x1, f1
        x1 = x2
    return math.nan, math.nan


@numba.njit(cache=True, inline="always", error_model="numpy", fastmath=_FAST)
def swing_guess(target: float, a1: float, s1: float, a2: float, s2: float) -> tuple[float, float]:
    """A start ``a_s`` for the swing ``target`` and the slope da_s/dA there, from the
    swings solved before on the same row: ``a1`` -> ``s1`` (the last one) and ``a2``
    -> ``s2`` (the one before; NaN where there is none). From two, the line through
    them; from one, the half drop in proportion to the swing; none (or a start NaN):
    NaN, the secant's own fixed point (:func:`swing_ends`)."""
    if not (math.isfinite(s1) and a1 > 0.0):
        return math.nan, math.nan
    if math.isfinite(s2) and a2 != a1:
        slope = (s1 - s2) / (a1 - a2)
        return s1 + slope * (target - a1), slope
    return target * (s1 / a1), s1 / a1
