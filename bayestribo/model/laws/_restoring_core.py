r"""The compiled half-cycle integrator of a law on a nonlinear restoring force: a template.

The algorithm is described in :mod:`bayestribo.model.laws.nonlinear`. Like
:mod:`bayestribo.model.laws._core` this module is never compiled as it is: its
functions call ``drag``, ``friction`` (the law's terms), ``spring`` and ``potential``
(the restoring force's compiled ``V'(y)`` and ``V(y)``), which
:func:`bayestribo.model.laws.nonlinear.make_nonlinear_integrator` defines after its text
for one law and one restoring force, and the functions it shares with ``_core``
(``outside_domain``, ``geometric_rest``, ``finish``, ``swing_ends``), whose text
:mod:`bayestribo.model.laws._core_shared` holds and the generator writes after this
module's.

What stays apart from ``_core`` is the motion itself: a half cycle here is integrated
in τ (the linear spring's polar coordinates do not hold), ends at a root of y' rather
than at θ = π, starts from the swing of the undamped motion through the initial state
(Newton on V(a) = E rather than the linear spring's fixed point), sticks where
|V'(Y)| <= ρμ rather than |Y| <= ρμ, and takes a fixed step; ``_core``'s step ladder,
averaged tail and creep to rest are built on the linear spring (its polar arcs, its
averaged motion, its force y) and have no counterpart here. ``grid``, ``one``,
``turns`` and ``half_cycle_end`` take the restoring force's coefficients ``k`` and the
step ``h``, which ``_core``'s do not, so they keep their own text.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numba
import numpy as np
from numpy.typing import NDArray

from bayestribo.model.laws._core_shared import (
    _FAST,
    _MAX_HALF_CYCLES,
    _MAX_PAST_HALF_CYCLES,
    _TAIL_TOLERANCE,
)

if TYPE_CHECKING:  # defined for each law and restoring force after this text
    from bayestribo.model.laws._core_shared import (
        finish,
        geometric_rest,
        outside_domain,
        swing_ends,
        swing_guess,
    )

    def drag(w: float, c: NDArray) -> float: ...

    def friction(a: float, c: NDArray) -> float: ...

    def spring(y: float, k: NDArray) -> float: ...

    def potential(y: float, k: NDArray) -> float: ...

    HAS_FRICTION: bool = False
    HAS_DRAG: bool = True

#: Runge-Kutta steps per π of τ (a linear oscillator's half cycle) when none are given.
DEFAULT_STEPS = 40
# A half cycle still moving after this long (τ) is an overdamped arc: outside the law's
# domain (its row of Π is NaN).
_MAX_HALF_SPAN = 40.0 * math.pi
# Newton iterations for the turning point of the undamped motion at a given energy.
_TURN_ITERATIONS = 40


@numba.njit(cache=True, inline="always", error_model="numpy", fastmath=_FAST)
def acceleration(y: float, v: float, sgn: float, mu: float, c: NDArray, k: NDArray) -> float:
    """y'' = -V'(y) - sgn (g(|y'|) + μ), the direction of motion ``sgn`` held fixed."""
    g = drag(abs(v), c) if HAS_DRAG else 0.0
    return -spring(y, k) - sgn * (g + mu)


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def step(
    y: float, v: float, cum: float, h: float, sgn: float, mu: float, c: NDArray, k: NDArray
) -> tuple[float, float, float]:
    """One classical Runge-Kutta step of (y, y', C = ∫E dτ) by ``h`` (of either sign),
    E = ½y'² + V(y)."""
    a1 = acceleration(y, v, sgn, mu, c, k)
    e1 = 0.5 * v * v + potential(y, k)
    y2 = y + 0.5 * h * v
    v2 = v + 0.5 * h * a1
    a2 = acceleration(y2, v2, sgn, mu, c, k)
    e2 = 0.5 * v2 * v2 + potential(y2, k)
    y3 = y + 0.5 * h * v2
    v3 = v + 0.5 * h * a2
    a3 = acceleration(y3, v3, sgn, mu, c, k)
    e3 = 0.5 * v3 * v3 + potential(y3, k)
    y4 = y + h * v3
    v4 = v + h * a3
    a4 = acceleration(y4, v4, sgn, mu, c, k)
    e4 = 0.5 * v4 * v4 + potential(y4, k)
    sixth = h / 6.0
    return (
        y + sixth * (v + 2.0 * v2 + 2.0 * v3 + v4),
        v + sixth * (a1 + 2.0 * a2 + 2.0 * a3 + a4),
        cum + sixth * (e1 + 2.0 * e2 + 2.0 * e3 + e4),
    )


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def turning_amplitude(energy: float, k: NDArray) -> float:
    """The swing a > 0 of the undamped motion of energy E: V(a) = E (Newton's method from
    √(2E), the linear spring's)."""
    a = math.sqrt(2.0 * energy)
    for _ in range(_TURN_ITERATIONS):
        f = spring(a, k)
        if not f > 0.0:
            return math.nan
        da = (potential(a, k) - energy) / f
        a -= da
        if abs(da) <= 1e-15 * a:
            break
    return a


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def stuck(y: float, mu: float, ratio: float, k: NDArray) -> bool:
    """At rest at the turning point y: the spring's force within the static friction
    ρμ (and the kinetic μ, which a motion could not overcome)."""
    f = abs(spring(y, k))
    return f <= ratio * mu or f <= mu


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def root_fraction(v0: float, a0: float, v1: float, a1: float, h: float) -> float:
    """Where in [0, 1] of a step the cubic Hermite interpolant of y' (values v0, v1 and
    slopes a0, a1) vanishes (bisection then Newton on it)."""
    lo, hi = 0.0, 1.0
    s = v0 / (v0 - v1) if v0 != v1 else 0.5
    for _ in range(60):
        s2 = s * s
        s3 = s2 * s
        p = (
            (2.0 * s3 - 3.0 * s2 + 1.0) * v0
            + (s3 - 2.0 * s2 + s) * h * a0
            + (-2.0 * s3 + 3.0 * s2) * v1
            + (s3 - s2) * h * a1
        )
        dp = (
            (6.0 * s2 - 6.0 * s) * v0
            + (3.0 * s2 - 4.0 * s + 1.0) * h * a0
            + (-6.0 * s2 + 6.0 * s) * v1
            + (3.0 * s2 - 2.0 * s) * h * a1
        )
        if (p > 0.0) == (v0 > 0.0):
            lo = s
        else:
            hi = s
        nxt = s - p / dp if dp != 0.0 else 0.5 * (lo + hi)
        if not (lo < nxt < hi):
            nxt = 0.5 * (lo + hi)
        if abs(nxt - s) <= 1e-15:
            return nxt
        s = nxt
    return s


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def half_cycle(
    y: float,
    v: float,
    t: float,
    cum: float,
    sgn: float,
    mu: float,
    c: NDArray,
    k: NDArray,
    h: float,
    tau: NDArray,
    j: int,
    tau_end: float,
    out: NDArray,
    c_end: float,
) -> tuple[float, float, float, int, float, int]:
    """Integrate from (y, y') at τ = t, moving in the direction ``sgn``, to the next
    turning point (y' = 0), writing C(τ_j) = ∫₀^τ_j E of the grid points passed into
    ``out`` and C at ``tau_end`` when passed.

    Returns (y, τ, C) at the turning point, the next grid index, C at ``tau_end`` (NaN
    when not passed) and a status: 0 turned, 1 an overdamped arc (no turning point
    within :data:`_MAX_HALF_SPAN`), 2 the record ended (every grid point and
    ``tau_end`` passed; the state is then not at a turning point).
    """
    n_t = tau.size
    start = t
    while True:
        yn, vn, cn = step(y, v, cum, h, sgn, mu, c, k)
        span = h
        turned = sgn * vn <= 0.0
        if turned:
            a0 = acceleration(y, v, sgn, mu, c, k)
            a1 = acceleration(yn, vn, sgn, mu, c, k)
            s = root_fraction(v, a0, vn, a1, h)
            span = s * h
            yn, vn, cn = step(y, v, cum, span, sgn, mu, c, k)
            for _ in range(2):  # Newton on y' = 0 with the integrator itself
                at = acceleration(yn, vn, sgn, mu, c, k)
                if at == 0.0 or vn == 0.0:
                    break
                dt = -vn / at
                yn, vn, cn = step(yn, vn, cn, dt, sgn, mu, c, k)
                span += dt
        # the grid points and the end of the record inside this step
        while j < n_t and tau[j] < t + span:
            out[j] = step(y, v, cum, tau[j] - t, sgn, mu, c, k)[2]
            j += 1
        if math.isnan(c_end) and tau_end < t + span:
            c_end = step(y, v, cum, tau_end - t, sgn, mu, c, k)[2]
        y, v, cum = yn, vn, cn
        t += span
        if turned:
            return y, t, cum, j, c_end, 0
        if j >= n_t and not math.isnan(c_end):
            return y, t, cum, j, c_end, 2
        if t - start > _MAX_HALF_SPAN or not math.isfinite(y + v):
            return y, t, cum, j, c_end, 1


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def start_state(y0: float, yp0: float, c: NDArray, k: NDArray) -> tuple[float, float]:
    """The direction of the first half cycle and its friction μ (at the swing of the
    undamped motion through the initial state when it starts inside a half cycle)."""
    if yp0 == 0.0:
        sgn = -1.0 if y0 > 0.0 else 1.0
        a = abs(y0)
    else:
        sgn = 1.0 if yp0 > 0.0 else -1.0
        a = turning_amplitude(0.5 * yp0 * yp0 + potential(y0, k), k)
    mu = friction(a, c) if HAS_FRICTION else 0.0
    return sgn, mu


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def one(
    tau: NDArray,
    y0: float,
    c: NDArray,
    k: NDArray,
    ratio: float,
    yp0: float,
    tau_end: float,
    steps: int,
    out: NDArray,
) -> int:
    n_t = tau.size
    h = math.pi / steps
    sgn, mu = start_state(y0, yp0, c, k)
    y = y0
    v = yp0
    t = 0.0
    cum = 0.0
    j = 0
    c_end = math.nan
    stopped = (yp0 == 0.0 and stuck(y0, mu, ratio, k)) or (y0 == 0.0 and yp0 == 0.0)
    last = 0.0
    before = 0.0
    n_half = 0
    n_past = 0
    while not stopped:
        if mu < 0.0 or not math.isfinite(mu):
            return outside_domain(out)
        c_start = cum
        y, t, cum, j, c_end, status = half_cycle(
            y, v, t, cum, sgn, mu, c, k, h, tau, j, tau_end, out, c_end
        )
        if status == 1:
            return outside_domain(out)
        if status == 2:
            break
        v = 0.0
        before = last
        last = cum - c_start
        n_half += 1
        a = abs(y)
        mu = friction(a, c) if HAS_FRICTION else 0.0
        if y == 0.0 or stuck(y, mu, ratio, k):
            break
        sgn = -1.0 if y > 0.0 else 1.0
        if j >= n_t and not math.isnan(c_end):
            break
        if t > tau_end and j >= n_t:
            break
        if math.isinf(tau_end) and j >= n_t:
            n_past += 1
            if last < _TAIL_TOLERANCE * cum:
                cum += geometric_rest(last, before)
                break
            if n_past >= _MAX_PAST_HALF_CYCLES:
                break
        if n_half >= _MAX_HALF_CYCLES:
            break
    return finish(out, tau, j, c_end, cum, tau_end)


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def grid(
    tau: NDArray,
    y0: NDArray,
    coef: NDArray,
    k: NDArray,
    ratio: NDArray,
    yp0: float,
    tau_end: float,
    steps: int,
) -> tuple[NDArray, NDArray]:
    out = np.empty((y0.size, tau.size))
    status = np.zeros(y0.size, dtype=np.int64)
    for p in range(y0.size):
        status[p] = one(tau, y0[p], coef[p], k, ratio[p], yp0, tau_end, steps, out[p])
    return out, status


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def turns(
    y0: float,
    c: NDArray,
    k: NDArray,
    ratio: float,
    yp0: float,
    tau_max: float,
    max_count: int,
    steps: int,
) -> tuple[NDArray, NDArray]:
    """Turning times τ_n and positions Y_n of one trajectory (the initial state first
    when y'₀ = 0), until the motion stops, τ passes ``tau_max`` or ``max_count``
    turning points."""
    h = math.pi / steps
    times = np.empty(max_count)
    where = np.empty(max_count)
    none = np.empty(0)
    sgn, mu = start_state(y0, yp0, c, k)
    n = 0
    if yp0 == 0.0:
        times[0] = 0.0
        where[0] = y0
        n = 1
        if y0 == 0.0 or stuck(y0, mu, ratio, k):
            return times[:n], where[:n]
    y = y0
    v = yp0
    t = 0.0
    cum = 0.0
    while n < max_count and t <= tau_max and mu >= 0.0:
        y, t, cum, _, _, status = half_cycle(
            y, v, t, cum, sgn, mu, c, k, h, none, 0, math.inf, none, math.nan
        )
        if status != 0:
            break
        v = 0.0
        times[n] = t
        where[n] = y
        n += 1
        mu = friction(abs(y), c) if HAS_FRICTION else 0.0
        if y == 0.0 or stuck(y, mu, ratio, k):
            break
        sgn = -1.0 if y > 0.0 else 1.0
    return times[:n], where[:n]


# Gauss-Legendre nodes of the averaged loss per cycle (in φ, x = A sin φ).
_GL_X, _GL_W = np.polynomial.legendre.leggauss(48)


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def cycle_dissipation(a: float, c: NDArray, k: NDArray) -> float:
    """The energy lost over one cycle of the undamped motion of swing ``a``, to first
    order in the loss: ``2(∫_{-a}^{a} g(v(x)) dx + 2μ(a) a)``, v(x) = √(2(V(a) - V(x)))
    (docs/restoring.md, Eq. 3), by Gauss-Legendre in φ (x = a sin φ: v ∝ cos φ near
    the ends, no singularity)."""
    total = 0.0
    if HAS_DRAG:
        e = potential(a, k)
        for i in range(_GL_X.size):
            phi = 0.5 * math.pi * _GL_X[i]
            x = a * math.sin(phi)
            v = math.sqrt(max(2.0 * (e - potential(x, k)), 0.0))
            total += _GL_W[i] * drag(v, c) * a * math.cos(phi) * 0.5 * math.pi
    mu = friction(a, c) if HAS_FRICTION else 0.0
    return 2.0 * (total + 2.0 * mu * a)


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def dissipation(coef: NDArray, k: NDArray, amplitudes: NDArray) -> NDArray:
    """:func:`cycle_dissipation` for each row of ``coef`` (P, K) at each amplitude (A,):
    shape (P, A)."""
    out = np.empty((coef.shape[0], amplitudes.size))
    for p in range(coef.shape[0]):
        for j in range(amplitudes.size):
            out[p, j] = cycle_dissipation(amplitudes[j], coef[p], k)
    return out


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def half_cycle_end(a: float, c: NDArray, aux: tuple[NDArray, float]) -> float:
    """|Y| at the end of the half cycle from rest at the turning point ``a`` > 0,
    static friction ignored (NaN when the motion cannot leave ``a``, the drag stops it
    before it turns, or it ends on the side it started); ``aux`` the restoring force's
    coefficients ``k`` and the step ``h``."""
    k, h = aux
    mu = friction(a, c) if HAS_FRICTION else 0.0
    if not (spring(a, k) > mu) or mu < 0.0:
        return math.nan
    none = np.empty(0)
    y, _, _, _, _, status = half_cycle(
        a, 0.0, 0.0, 0.0, -1.0, mu, c, k, h, none, 0, math.inf, none, math.nan
    )
    if status != 0 or y >= 0.0:
        return math.nan
    return -y


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def swing_drops(coef: NDArray, k: NDArray, swing: NDArray, steps: int) -> NDArray:
    """The energy V(a_s) - V(a_e) lost over the half cycle whose swing ½(a_s + a_e) is
    each of ``swing`` (S,), for each row of ``coef`` (P, K): shape (P, S). a_s by the
    secant method on ½(a_s + a_e(a_s)) = A
    (:func:`~bayestribo.model.laws._core_shared.swing_ends`); NaN where no such half
    cycle exists."""
    aux = (k, math.pi / steps)
    out = np.empty((coef.shape[0], swing.size))
    for p in range(coef.shape[0]):
        # each swing started from the ones solved before on the row (swing_guess)
        a1 = s1 = a2 = s2 = math.nan
        for j in range(swing.size):
            guess, slope = swing_guess(swing[j], a1, s1, a2, s2)
            a_s, a_e = swing_ends(swing[j], coef[p], aux, guess, slope)
            a2, s2, a1, s1 = a1, s1, swing[j], a_s
            out[p, j] = math.nan if math.isnan(a_s) else potential(a_s, k) - potential(a_e, k)
    return out
