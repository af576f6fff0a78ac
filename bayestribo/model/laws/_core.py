"""The compiled half-cycle integrator: a template, compiled once per law.

The algorithm is described in :mod:`bayestribo.model.laws.integrator`. This module is
never compiled as it is: its functions call ``drag``, ``friction`` and read
``HAS_FRICTION``, which it does not define, and the functions it shares with the
template of the laws on a nonlinear restoring force (``outside_domain``,
``geometric_rest``, ``finish``, ``swing_ends``), which
:mod:`bayestribo.model.laws._core_shared` holds. :func:`bayestribo.model.laws.integrator.
make_integrator` writes its text, then the shared text, then those definitions for one
law (imports of the terms' compiled forces and their sum) to a file of the law cache,
and imports that file: every function is then compiled with ``cache=True`` and loaded
from numba's cache by later processes.
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

# the ladder of step counts, the nodes of a half cycle and the ladder's node tables
# (frozen into the functions that read them) depend on no law: compiled and computed
# once, in their own module, for every law
from bayestribo.model.laws._ladder import LADDER, nodes
from bayestribo.model.laws._ladder import OFFSETS as _OFFSETS
from bayestribo.model.laws._ladder import TABLES as _TABLES

if TYPE_CHECKING:  # defined for each law after this text (see the module notes)
    from bayestribo.model.laws._core_shared import (
        finish,
        geometric_rest,
        outside_domain,
        swing_ends,
        swing_guess,
    )
    from bayestribo.model.laws._creep import overdamped_end

    def drag(w: float, c: NDArray) -> float: ...

    def friction(a: float, c: NDArray) -> float: ...

    def friction_off(c: NDArray) -> bool: ...

    HAS_FRICTION: bool = False
    HAS_DRAG: bool = True

#: Runge-Kutta steps per half cycle: 0 chooses them per half cycle (see
#: :func:`make_integrator`); a positive number fixes them and integrates every half
#: cycle (the reference of convergence tests: no shortcut past the record); a negative
#: one fixes -steps and shortens the sum past the record as 0 does, with the same
#: half cycles (the coarse model of the optimiser's multi-start): it stops where the
#: half cycles hold less than _TAIL_TOLERANCE of the sum, and takes the rest up to the
#: cap of half cycles past the record from the averaged flow of those -steps half
#: cycles, within _AVERAGED_TOLERANCE of what summing them would give.
DEFAULT_STEPS = 0
#: The error of Π, relative to Π(0), that the steps chosen per half cycle (DEFAULT_STEPS)
#: are set for: measured against 1024 fixed steps, 3e-10 to 5e-9 over the drags and
#: frictions of tests/test_model_laws_tolerance.py. A caller may allow more
#: (:meth:`bayestribo.model.laws.Law.pi_grid`'s ``tolerance``, the integrator's
#: ``error_weight`` = tolerance / BASE_ERROR): the steps fall as its fourth root.
BASE_ERROR = 2e-9
# Steps ≈ _STEP_SCALE √ζ_e keep Π within ~2e-9 of Π(0): the error of the scheme measured
# against the closed form grows as ζ² h⁴ (1.4e-9 at ζ = 0.01 and 48 steps; 2.7e-8 at
# ζ = 0.2 and 96 steps), so h ∝ ζ^(-1/2) holds it constant.
_STEP_SCALE = 440.0
# The fewest steps of a half cycle inside the record: with little damping the motion
# lasts many half cycles, each one's error in r carried into the next ones.
_MIN_STEPS = 32
# Past the record (a law without friction, summed to the end of motion) the half cycles
# that halve the energy may together be off by this fraction of the scheme's error
# inside the record (each by (1 - ρ) of it, ρ the ratio of successive half cycles' Π):
# a half cycle's steps follow from the error ∝ h⁴ relative to its own share of Π(0).
_TAIL_SHARE = 1e-2
# The averaged tail (see :func:`averaged_tail`): tried once the half cycles past the
# record lose less than this fraction of their amplitude each and more than
# _AVERAGED_MIN_HALF_CYCLES of them remain; its nodes, the most spans down the
# amplitudes, the halvings of a span whose interpolants miss their tolerance (the
# local power of a drag that is a sum of terms changes along it), and the tolerance on
# the Chebyshev coefficients of its interpolants (relative error of dn/du and dS/du).
_AVERAGED_DROP = 0.02
_AVERAGED_MIN_HALF_CYCLES = 64
_AVERAGED_NODES = 7
_AVERAGED_SPANS = 8
_AVERAGED_HALVINGS = 3
_AVERAGED_TOLERANCE = 1e-8
# Fixed-point iterations for the friction of a start inside a half cycle.
_START_ITERATIONS = 6


@numba.njit(cache=True, inline="always", error_model="numpy", fastmath=_FAST)
def rates_at(s: float, co: float, r: float, mu: float, g: float) -> tuple[float, float, float]:
    """dr/dθ, dτ/dθ and dI/dθ at a node where the drag is ``g`` = g(r sin θ)."""
    inv = 1.0 / (1.0 - co * g / r)
    energy = 0.5 * (mu * mu + 2.0 * mu * r * co + r * r)
    return -s * g * inv, inv, energy * inv


@numba.njit(cache=True, inline="always", error_model="numpy", fastmath=_FAST)
def rates(s: float, co: float, r: float, mu: float, c: NDArray) -> tuple[float, float, float]:
    return rates_at(s, co, r, mu, drag(r * s, c))


@numba.njit(cache=True, inline="always", error_model="numpy", fastmath=_FAST)
def energy_and_rate(
    s: float, co: float, r: float, mu: float, g: float, e_at: NDArray, k: int
) -> None:
    """E and its rate E' = -|y'| (g(|y'|) + μ) at a node where the drag is ``g``, into
    ``e_at[:, k]``."""
    w = r * s
    e_at[0, k] = 0.5 * (mu * mu + 2.0 * mu * r * co + r * r)
    e_at[1, k] = -w * (g + mu)


@numba.njit(cache=True, inline="always", error_model="numpy", fastmath=_FAST)
def arc_integral(t: float, r: float, mu: float, theta0: float) -> float:
    """∫₀ᵗ E dτ along a half cycle without drag (θ = θ₀ + τ, r constant)."""
    return 0.5 * (mu * mu + r * r) * t + mu * r * (math.sin(theta0 + t) - math.sin(theta0))


@numba.njit(cache=True, inline="always", error_model="numpy", fastmath=_FAST)
def choose_steps(r: float, c: NDArray, weight: float, tail: bool = False) -> int:
    """Index in LADDER of the steps for a half cycle of amplitude r about its centre:
    from the drag's equivalent damping at the peak speed, ζ_e = g(r)/(2r). ``weight``
    >= 1 is how many times the scheme's usual relative error the half cycle may have,
    which divides the steps by its fourth root (the error ∝ ζ_e² h⁴); never fewer than
    _MIN_STEPS, but in a half cycle of the ``tail`` past the record given a weight."""
    zeta_e = drag(r, c) / (2.0 * r) if r > 0.0 else 0.0
    want = _STEP_SCALE * math.sqrt(max(zeta_e, 0.0))
    if weight > 1.0:
        want /= math.sqrt(math.sqrt(weight))
    if not (tail and weight > 1.0):
        want = max(want, _MIN_STEPS)
    for i in range(LADDER.size):
        if LADDER[i] >= want:
            return i
    return LADDER.size - 1


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def half_cycle(
    table: NDArray,
    r0: float,
    mu: float,
    c: NDArray,
    steps: int,
    tau_at: NDArray,
    c_at: NDArray,
    e_at: NDArray,
) -> float:
    """Integrate one half cycle over the angles of ``table`` (from :func:`nodes`);
    fills τ, C and E at the steps (relative to the half cycle's start) and returns
    r(π) (NaN for an overdamped arc)."""
    h = 1.0 / steps
    r = r0
    tau = 0.0
    cum = 0.0
    tau_at[0] = 0.0
    c_at[0] = 0.0
    # the drag at a node, shared by its energy rate and the next step's first stage
    g = drag(r * table[0, 0], c)
    energy_and_rate(table[0, 0], table[1, 0], r, mu, g, e_at, 0)
    for k in range(steps):
        i0 = 2 * k
        a1, b1, e1 = rates_at(table[0, i0], table[1, i0], r, mu, g)
        d = table[2, i0]
        a1 *= d
        b1 *= d
        e1 *= d
        s1 = table[0, i0 + 1]
        c1 = table[1, i0 + 1]
        d = table[2, i0 + 1]
        ra = r + 0.5 * h * a1
        a2, b2, e2 = rates(s1, c1, ra, mu, c)
        a2 *= d
        b2 *= d
        e2 *= d
        rb = r + 0.5 * h * a2
        a3, b3, e3 = rates(s1, c1, rb, mu, c)
        a3 *= d
        b3 *= d
        e3 *= d
        rc = r + h * a3
        a4, b4, e4 = rates(table[0, i0 + 2], table[1, i0 + 2], rc, mu, c)
        d = table[2, i0 + 2]
        a4 *= d
        b4 *= d
        e4 *= d
        # an overdamped arc: the drag turns θ back before y' = 0 (D <= 0)
        if not (b1 >= 0.0 and b2 > 0.0 and b3 > 0.0 and b4 >= 0.0):
            return math.nan
        if not (ra > 0.0 and rb > 0.0 and rc > 0.0):
            return math.nan
        r += h * (a1 + 2.0 * a2 + 2.0 * a3 + a4) / 6.0
        tau += h * (b1 + 2.0 * b2 + 2.0 * b3 + b4) / 6.0
        cum += h * (e1 + 2.0 * e2 + 2.0 * e3 + e4) / 6.0
        tau_at[k + 1] = tau
        c_at[k + 1] = cum
        g = drag(r * table[0, i0 + 2], c)
        energy_and_rate(table[0, i0 + 2], table[1, i0 + 2], r, mu, g, e_at, k + 1)
    return r


@numba.njit(cache=True, inline="always", error_model="numpy", fastmath=_FAST)
def hermite(t: float, k: int, tau_at: NDArray, c_at: NDArray, e_at: NDArray) -> float:
    """C at τ = t inside step k: the quintic Hermite polynomial of C, C' = E and
    C'' = E' at the step's ends (error O(h⁶))."""
    t0 = tau_at[k]
    h = tau_at[k + 1] - t0
    if h <= 0.0:
        return c_at[k]
    s = (t - t0) / h
    s2 = s * s
    s3 = s2 * s
    s4 = s3 * s
    s5 = s4 * s
    return (
        (1.0 - 10.0 * s3 + 15.0 * s4 - 6.0 * s5) * c_at[k]
        + (s - 6.0 * s3 + 8.0 * s4 - 3.0 * s5) * h * e_at[0, k]
        + (0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5) * h * h * e_at[1, k]
        + (10.0 * s3 - 15.0 * s4 + 6.0 * s5) * c_at[k + 1]
        + (-4.0 * s3 + 7.0 * s4 - 3.0 * s5) * h * e_at[0, k + 1]
        + (0.5 * s3 - s4 + 0.5 * s5) * h * h * e_at[1, k + 1]
    )


@numba.njit(cache=True, inline="always", error_model="numpy", fastmath=_FAST)
def interpolate(t: float, steps: int, tau_at: NDArray, c_at: NDArray, e_at: NDArray) -> float:
    """C at τ = t inside a half cycle of ``steps`` steps: the step holding t by
    bisection, then :func:`hermite`."""
    lo = 0
    hi = steps
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if tau_at[mid] <= t:
            lo = mid
        else:
            hi = mid
    return hermite(t, lo, tau_at, c_at, e_at)


# Gauss-Legendre nodes and weights on [-1, 1] for the averaged tail's integrals
_GL_X, _GL_W = np.polynomial.legendre.leggauss(16)


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def turn_to_turn(
    a: float,
    c: NDArray,
    ratio: float,
    tables: NDArray,
    offsets: NDArray,
    tau_at: NDArray,
    c_at: NDArray,
    e_at: NDArray,
    fixed: int,
) -> tuple[float, float]:
    """|Y| of the next turning point and ∫E over the half cycle from rest at the turning
    point ``a`` > 0, with more steps than the ladder's (its error about ten times
    smaller), or with ``fixed`` > 0 steps (``tables`` then that count's node table):
    the half cycle of a model with fixed steps; NaN for both where the motion stops at
    ``a`` or cannot turn."""
    mu = friction(a, c) if HAS_FRICTION else 0.0
    r = a - mu
    if not (mu >= 0.0 and r > 0.0 and a > ratio * mu):
        return math.nan, math.nan
    if HAS_DRAG:
        if fixed > 0:
            steps = fixed
            table = tables
        else:
            k = min(choose_steps(r, c, 1.0) + 3, LADDER.size - 1)
            steps = LADDER[k]
            table = tables[:, offsets[k] : offsets[k] + 2 * steps + 1]
        r_end = half_cycle(table, r, mu, c, steps, tau_at, c_at, e_at)
        c_half = c_at[steps]
    else:
        r_end = r
        c_half = arc_integral(math.pi, r, mu, 0.0)
    y_turn = mu - r_end
    if not (y_turn < 0.0):
        return math.nan, math.nan
    return -y_turn, c_half


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def flow_at(
    a: float,
    c: NDArray,
    ratio: float,
    tables: NDArray,
    offsets: NDArray,
    tau_at: NDArray,
    c_at: NDArray,
    e_at: NDArray,
    fixed: int,
) -> tuple[float, float, float]:
    """V = -da/dn, J = dS/dn and d²a/dn² at the turning point ``a`` of the smooth flow
    whose values at whole n are the turning points (n counts half cycles, S sums their
    ∫E): one-sided five-point differences over the four half cycles from ``a`` (error
    ~ε⁴/5 of each for a relative drop ε per half cycle), each half cycle with ``fixed``
    steps where > 0 (:func:`turn_to_turn`). NaN where one of them stops."""
    xs = np.empty(5)
    cs = np.empty(5)
    xs[0] = a
    cs[0] = 0.0
    for i in range(4):
        nxt, part = turn_to_turn(xs[i], c, ratio, tables, offsets, tau_at, c_at, e_at, fixed)
        if not math.isfinite(nxt):
            return math.nan, math.nan, math.nan
        xs[i + 1] = nxt
        cs[i + 1] = cs[i] + part
    v = (25.0 * xs[0] - 48.0 * xs[1] + 36.0 * xs[2] - 16.0 * xs[3] + 3.0 * xs[4]) / 12.0
    j = (-25.0 * cs[0] + 48.0 * cs[1] - 36.0 * cs[2] + 16.0 * cs[3] - 3.0 * cs[4]) / 12.0
    curve = (35.0 * xs[0] - 104.0 * xs[1] + 114.0 * xs[2] - 56.0 * xs[3] + 11.0 * xs[4]) / 12.0
    return v, j, curve


@numba.njit(cache=True, inline="always", error_model="numpy", fastmath=_FAST)
def chebyshev_value(x: float, nodes: NDArray, values: NDArray) -> float:
    """The polynomial through ``values`` at the Chebyshev points ``nodes`` (cos(kπ/(K-1)),
    k = 0 .. K-1) at x in [-1, 1], by the barycentric formula."""
    num = 0.0
    den = 0.0
    last = nodes.size - 1
    for k in range(nodes.size):
        d = x - nodes[k]
        if d == 0.0:
            return values[k]
        w = (1.0 if k % 2 == 0 else -1.0) * (0.5 if k == 0 or k == last else 1.0) / d
        num += w * values[k]
        den += w
    return num / den


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def averaged_rate(a: float, c: NDArray) -> float:
    """V₁(a) = (1 + μ'(a)) (∫₀^π sin θ g(a sin θ) dθ + 2μ(a)): the rate of decay of the
    turning points per half cycle of the averaged motion from the turning point ``a``,
    to second order in the drop per half cycle (the drag's first-order rate is odd in
    it; the friction, fixed at each half cycle's start, adds the factor 1 + μ'). The
    drag's integral by Gauss-Legendre in the stretched angle of :func:`nodes`, smooth
    at the ends for a drag not smooth at zero speed."""
    total = 0.0
    if HAS_DRAG:
        two_pi = 2.0 * math.pi
        for i in range(_GL_X.size):
            psi = 0.5 * (_GL_X[i] + 1.0)
            th = math.pi * (psi - math.sin(two_pi * psi) / two_pi)
            s = math.sin(th)
            total += _GL_W[i] * s * drag(a * s, c) * 0.5 * math.pi * (1.0 - math.cos(two_pi * psi))
    if not HAS_FRICTION:
        return total
    mu = friction(a, c)
    slope = (friction(a * (1.0 + 1e-4), c) - friction(a * (1.0 - 1e-4), c)) / (2e-4 * a)
    return (1.0 + slope) * (total + 2.0 * mu)


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def tail_integral(
    lo: float,
    hi: float,
    u0: float,
    q: float,
    z_lo: float,
    nodes: NDArray,
    h_n: NDArray,
    h_s: NDArray,
    c: NDArray,
    energy: bool,
) -> float:
    """∫ dn/du (or dS/du with ``energy``) over u in [lo, hi] (Gauss-Legendre, 16 nodes):
    dn/du = a/V = (a/V₁) exp(h_n), dS/du = aJ/V = (a/V₁)(πa²/2) exp(h_n + h_s), with h_n
    and h_s interpolated at the Chebyshev points ``nodes`` of z = exp(q(u - u0)) over
    [z_lo, 1]."""
    half = 0.5 * (hi - lo)
    mid = 0.5 * (hi + lo)
    total = 0.0
    for i in range(_GL_X.size):
        u = mid + half * _GL_X[i]
        a = math.exp(u)
        x = (2.0 * math.exp(q * (u - u0)) - 1.0 - z_lo) / (1.0 - z_lo)
        expo = chebyshev_value(x, nodes, h_n)
        value = a / averaged_rate(a, c)
        if energy:
            expo += chebyshev_value(x, nodes, h_s)
            value *= 0.5 * math.pi * a * a
        total += _GL_W[i] * value * math.exp(expo)
    return total * half


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def interpolants(
    a0: float,
    v0: float,
    j0: float,
    curve0: float,
    q: float,
    z_lo: float,
    c: NDArray,
    ratio: float,
    tables: NDArray,
    offsets: NDArray,
    tau_at: NDArray,
    c_at: NDArray,
    e_at: NDArray,
    fixed: int,
    nodes: NDArray,
    h_n: NDArray,
    h_s: NDArray,
) -> tuple[bool, float, float, float, float]:
    """Fill ``nodes`` (Chebyshev points of z = (a/a0)^q over [``z_lo``, 1]) and the
    factors' logarithms ``h_n`` = ln(V₁/V) and ``h_s`` = ln(J/J₁) there, from the flow
    of the law's half cycles (:func:`flow_at`; at a0 its V, J and d²a/dn² given):
    (taken, a, V, J, d²a/dn² at the lower end z_lo), taken False where a node's motion
    stops or drops by _AVERAGED_DROP or more per half cycle, or where either
    interpolant's last two Chebyshev coefficients exceed _AVERAGED_TOLERANCE."""
    k_n = nodes.size
    a, v, j, curve = a0, v0, j0, curve0
    for k in range(k_n):
        nodes[k] = math.cos(math.pi * k / (k_n - 1))
        z = 0.5 * ((nodes[k] + 1.0) * (1.0 - z_lo)) + z_lo
        if k > 0:
            a = a0 * z ** (1.0 / q)
            v, j, curve = flow_at(a, c, ratio, tables, offsets, tau_at, c_at, e_at, fixed)
        if not (v > 0.0 and j > 0.0) or v > _AVERAGED_DROP * a:
            return False, a, v, j, curve
        h_n[k] = math.log(averaged_rate(a, c) / v)
        h_s[k] = math.log(j / (0.5 * math.pi * a * a))
    # the interpolants' last Chebyshev coefficients: their error
    for f in (h_n, h_s):
        for m in (k_n - 2, k_n - 1):
            coef = 0.0
            for k in range(k_n):
                w = 0.5 if k == 0 or k == k_n - 1 else 1.0
                coef += w * f[k] * math.cos(math.pi * m * k / (k_n - 1))
            coef *= 2.0 / (k_n - 1)
            if not abs(coef) <= _AVERAGED_TOLERANCE:
                return False, a, v, j, curve
    return True, a, v, j, curve


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def averaged_segment(
    a0: float,
    v0: float,
    j0: float,
    curve0: float,
    c: NDArray,
    ratio: float,
    n_rem: float,
    negligible: float,
    tables: NDArray,
    offsets: NDArray,
    tau_at: NDArray,
    c_at: NDArray,
    e_at: NDArray,
    fixed: int,
) -> tuple[int, float, float, float, float, float, float]:
    """One span of :func:`averaged_tail` from the turning point ``a0`` (V, J and d²a/dn²
    there given): (status, S, n, a, V, J, d²a/dn² at its lower end), status 0 where it
    cannot be trusted, 1 where the sum ends in it (S with the rest when negligible), 2
    where it goes on below it."""
    fail = (0, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan)
    if not (v0 > 0.0 and j0 > 0.0 and math.isfinite(curve0)) or v0 > _AVERAGED_DROP * a0:
        return fail
    eps = v0 / a0
    p = a0 * curve0 / (v0 * v0)  # d ln V / d ln a
    if not p > 0.95:
        return fail  # a decay that quickens down the tail: the exact sum ends soon
    # the span: to the end of the n_rem half cycles or to where the rest is negligible
    if abs(p - 1.0) < 1e-3:
        span = n_rem * eps
    elif p > 1.0:
        span = math.log1p(n_rem * (p - 1.0) * eps) / (p - 1.0)
    elif n_rem * (1.0 - p) * eps < 1.0:
        span = -math.log1p(-n_rem * (1.0 - p) * eps) / (1.0 - p)
    else:
        span = math.inf
    if p < 3.0:
        rest = a0 * j0 / v0 / (3.0 - p)  # S below u0 on the power law
        if rest > negligible:
            span = min(span, math.log(rest / negligible) / (3.0 - p))
    if not (span > 0.0 and math.isfinite(span)):
        return fail
    # the span's interpolants, on a half, a quarter ... of it where they miss their
    # tolerance (a drag whose local power changes down the span: the next spans go on
    # from its lower end, each with its own power law)
    u0 = math.log(a0)
    q = max(p - 1.0, 0.05)
    nodes = np.empty(_AVERAGED_NODES)
    h_n = np.empty(_AVERAGED_NODES)  # ln(V₁/V)
    h_s = np.empty(_AVERAGED_NODES)  # ln(J/J₁)
    full = 1.2 * span + 0.1
    taken = False
    width = full
    z_lo = 0.0
    a, v, j = a0, v0, j0
    for halving in range(_AVERAGED_HALVINGS + 1):
        width = full * 0.5**halving
        if eps * math.exp((1.0 - p) * width) > _AVERAGED_DROP:
            continue  # the drop grows past the bound down the span
        z_lo = math.exp(-q * width)
        taken, a, v, j, curve = interpolants(
            a0,
            v0,
            j0,
            curve0,
            q,
            z_lo,
            c,
            ratio,
            tables,
            offsets,
            tau_at,
            c_at,
            e_at,
            fixed,
            nodes,
            h_n,
            h_s,
        )
        if taken:
            break
    if not taken:
        return fail
    # integrate down from u0, panel by panel, until n_rem half cycles are summed
    panels = int(width) + 1
    step = width / panels
    n_sum = 0.0
    s_sum = 0.0
    for i in range(panels):
        hi = u0 - i * step
        lo = hi - step
        n_part = tail_integral(lo, hi, u0, q, z_lo, nodes, h_n, h_s, c, False)
        if n_sum + n_part < n_rem:
            n_sum += n_part
            s_sum += tail_integral(lo, hi, u0, q, z_lo, nodes, h_n, h_s, c, True)
            continue
        # the end of the n_rem-th half cycle inside this panel: Newton within a bracket
        need = n_rem - n_sum
        left, right = lo, hi
        u = hi - need * step / n_part
        for _ in range(60):
            if not (left < u < right):
                u = 0.5 * (left + right)
            g = tail_integral(u, hi, u0, q, z_lo, nodes, h_n, h_s, c, False) - need
            if g > 0.0:
                left = u
            else:
                right = u
            rate = tail_integral(u, u + 1e-6, u0, q, z_lo, nodes, h_n, h_s, c, False) / 1e-6
            u_next = u + g / rate
            if abs(u_next - u) < 1e-13 * (1.0 + abs(u)):
                u = u_next
                break
            u = u_next
        s_sum += tail_integral(u, hi, u0, q, z_lo, nodes, h_n, h_s, c, True)
        return 1, s_sum, n_rem, math.nan, math.nan, math.nan, math.nan
    # the span ends before the n_rem half cycles: the rest below it negligible, or on
    lo = u0 - width
    ds = tail_integral(lo, lo + 1e-6, u0, q, z_lo, nodes, h_n, h_s, c, True) / 1e-6
    rest = ds / (3.0 - p) if p < 3.0 else math.inf
    if rest <= negligible:
        return 1, s_sum + rest, n_sum, math.nan, math.nan, math.nan, math.nan
    return 2, s_sum, n_sum, a, v, j, curve


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def averaged_tail(
    a0: float,
    c: NDArray,
    ratio: float,
    n_rem: int,
    negligible: float,
    tables: NDArray,
    offsets: NDArray,
    tau_at: NDArray,
    c_at: NDArray,
    e_at: NDArray,
    fixed: int = 0,
) -> float:
    """∑ of ∫E over the next ``n_rem`` half cycles from rest at the turning point
    ``a0`` (or over all of them where the rest falls below ``negligible``), from the
    averaged motion; NaN where it cannot be trusted (the caller integrates the half
    cycles then). The half cycles are the ladder's (``fixed`` 0; ``tables`` and
    ``offsets`` the ladder's) or of ``fixed`` steps each (``tables`` that count's node
    table), whose sum it then stands for.

    The turning points are the values at whole n of a smooth flow da/dn = -V(a) (n
    counting half cycles), and the sums of ∫E those of S with dS/dn = J(a): with
    u = ln a, n = ∫ a/V du and S = ∫ aJ/V du. V and J are the first-order averaged
    motion's (V₁ of :func:`averaged_rate`, J₁ = πa²/2) times factors 1 + O(ε²) (ε the
    relative drop per half cycle), measured at _AVERAGED_NODES amplitudes from four
    half cycles of the law's own motion each (:func:`flow_at`) and interpolated at
    Chebyshev points of z = (a/a0)^q, q = p - 1 for the local power law V ∝ a^p at
    the span's top (the factors' logarithms are then near polynomials in z); their
    last Chebyshev coefficients must be below _AVERAGED_TOLERANCE. Each span is chosen
    from that power law (:func:`averaged_segment`; halved up to _AVERAGED_HALVINGS
    times where its interpolants miss their tolerance), up to _AVERAGED_SPANS of them down
    the amplitudes (the local power changes along a decay whose drag is a sum of
    terms), and every node must drop by less than _AVERAGED_DROP per half cycle.
    """
    v, j, curve = flow_at(a0, c, ratio, tables, offsets, tau_at, c_at, e_at, fixed)
    a = a0
    total = 0.0
    left = float(n_rem)
    for _ in range(_AVERAGED_SPANS):
        status, part, count, a, v, j, curve = averaged_segment(
            a, v, j, curve, c, ratio, left, negligible, tables, offsets, tau_at, c_at, e_at, fixed
        )
        if status == 0:
            return math.nan
        total += part
        if status == 1:
            return total
        left -= count
    return math.nan


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def one(
    tau: NDArray,
    y0: float,
    c: NDArray,
    ratio: float,
    yp0: float,
    tau_end: float,
    fixed_steps: int,
    tables: NDArray,
    offsets: NDArray,
    out: NDArray,
    creep_end: float = math.inf,
    error_weight: float = 1.0,
) -> int:
    n_t = tau.size
    # fixed steps (either sign; see DEFAULT_STEPS), and whether the sum past the record
    # may be shortened (not for the reference, fixed_steps > 0)
    fixed = abs(fixed_steps)
    shorten = fixed_steps <= 0
    size = max(fixed, LADDER[-1]) + 1
    tau_at = np.empty(size)
    c_at = np.empty(size)
    e_at = np.empty((2, size))
    steps = 0
    # -- the first half cycle, in the frame where it starts at a positive turning point
    if yp0 == 0.0:
        a = abs(y0)
        mu = friction(a, c) if HAS_FRICTION else 0.0
        theta0 = 0.0
        r = a - mu
        if a <= ratio * mu or r <= 0.0:
            r = -1.0  # stuck from the start
    else:
        ym = -y0 if yp0 > 0.0 else y0
        vm = -abs(yp0)
        mu = friction(math.hypot(y0, yp0), c) if HAS_FRICTION else 0.0
        for _ in range(_START_ITERATIONS):
            if not HAS_FRICTION:
                break
            mu = friction(math.hypot(ym - mu, vm) + mu, c)
        u = ym - mu
        r = math.hypot(u, vm)
        theta0 = math.atan2(-vm, u)
    # -- sweep half cycles, evaluating C = ∫₀^τ E at the grid and at the end
    j = 0  # next grid point
    c_start = 0.0  # C at the start of the current half cycle
    t_start = 0.0  # τ at the start of the current half cycle
    c_end = math.nan  # C at T = min(stop, tau_end)
    stopped = r <= 0.0
    last = 0.0
    before = 0.0
    n_half = 0
    n_past = 0  # half cycles integrated past the record
    # A friction law whose friction terms are all off (coefficients at zero: μ_k = 0
    # on its bound) moves as the law without them, which no friction stops: its sum
    # past the record ends as that law's does (the same tail, within _TAIL_TOLERANCE),
    # not after the thousands of half cycles the drag takes to bring r to zero.
    frictionless = not HAS_FRICTION or friction_off(c)
    a_from = r + mu  # the turning point the current half cycle starts from
    a_try = math.inf  # the averaged tail is tried again below half this amplitude
    drop = math.nan  # the relative drop of the turning points over the last half cycle
    drop_before = math.nan
    while not stopped:
        if mu < 0.0:
            # a friction that falls with amplitude below zero: outside the law's domain
            return outside_domain(out)
        exact = not HAS_DRAG and fixed == 0
        if exact:
            # no drag: an arc of the undamped motion about the centre, in closed form
            r_end = r
            t_half = math.pi - theta0
            c_half = arc_integral(t_half, r, mu, theta0)
        else:
            if fixed > 0:
                steps = fixed
                table = tables if theta0 == 0.0 else nodes(theta0, steps)
            else:
                weight = error_weight
                past = j >= n_t and math.isinf(tau_end)
                tail = past and frictionless and mu == 0.0 and 0.0 < last < before
                if tail:
                    # past the record only the sum counts: each half cycle may be off by
                    # its share of it, over the ~1/(1 - ρ) half cycles that remain
                    weight *= _TAIL_SHARE * (1.0 - last / before) * c_start / last
                k = choose_steps(r, c, weight, tail)
                steps = LADDER[k]
                if theta0 == 0.0:
                    table = tables[:, offsets[k] : offsets[k] + 2 * steps + 1]
                else:
                    table = nodes(theta0, steps)
            r_end = half_cycle(table, r, mu, c, steps, tau_at, c_at, e_at)
            if not math.isfinite(r_end):
                if mu == 0.0:
                    # a drag that the decay has made stronger than the spring (a power
                    # law below α = 1): the motion ends by an overdamped creep to rest,
                    # integrated to its end (bayestribo.model.laws._creep); the row
                    # stays outside the law's domain where the creep never ends. Summed
                    # to the end of motion of a record that holds its stop, the creep
                    # ends where the record's does (creep_end), or where it begins if
                    # that is later: its ∫E past the record's stop is none of the data's
                    arc_at = tau_end if creep_end >= tau_end else max(creep_end, t_start)
                    arc, j, arc_end, t_cross, w_cross = overdamped_end(
                        theta0,
                        r,
                        c,
                        tau_at,
                        c_at,
                        e_at,
                        tau,
                        j,
                        t_start,
                        c_start,
                        arc_at,
                        out,
                    )
                    if math.isnan(c_end):
                        c_end = arc_end
                    if math.isfinite(t_cross):
                        # it crosses the centre after all: the half cycle goes on from
                        # there (θ = π/2) in the polar steps
                        t_start += t_cross
                        c_start += arc
                        r = w_cross
                        theta0 = 0.5 * math.pi
                        continue
                    if math.isfinite(arc):
                        c_start += arc
                        break
                return outside_domain(out)
            t_half = tau_at[steps]
            c_half = c_at[steps]
        t_next = t_start + t_half
        # grid points inside this half cycle
        while j < n_t and tau[j] < t_next:
            t_rel = tau[j] - t_start
            if exact:
                out[j] = c_start + arc_integral(t_rel, r, mu, theta0)
            else:
                out[j] = c_start + interpolate(t_rel, steps, tau_at, c_at, e_at)
            j += 1
        if tau_end < t_next and math.isnan(c_end):
            t_rel = tau_end - t_start
            if exact:
                c_end = c_start + arc_integral(t_rel, r, mu, theta0)
            else:
                c_end = c_start + interpolate(t_rel, steps, tau_at, c_at, e_at)
        before = last
        last = c_half
        c_start += c_half
        t_start = t_next
        n_half += 1
        # -- the next turning point
        y_turn = mu - r_end
        a = abs(y_turn)
        if y_turn >= 0.0:
            # the drag or friction ended the motion on the same side: at rest
            stopped = True
            break
        mu = friction(a, c) if HAS_FRICTION else 0.0
        if a <= ratio * mu or a - mu <= 0.0:
            stopped = True
            break
        r = a - mu
        theta0 = 0.0
        drop_before = drop
        drop = (a_from - a) / a_from
        a_from = a
        if not math.isnan(c_end) and j >= n_t:
            break  # the record ends inside the motion: nothing more to integrate
        if t_start > tau_end and j >= n_t:
            break
        if math.isinf(tau_end) and j >= n_t and ((frictionless and mu == 0.0) or shorten):
            # endless motion (no friction, or one that vanishes with the amplitude): sum
            # until the half cycles hold nothing, then a tail
            if last < _TAIL_TOLERANCE * c_start:
                c_start += geometric_rest(last, before)
                break
        if n_half >= _MAX_HALF_CYCLES:
            break
        if j >= n_t:
            n_past += 1
            if n_past >= _MAX_PAST_HALF_CYCLES:
                break
            remaining = min(_MAX_PAST_HALF_CYCLES - n_past, _MAX_HALF_CYCLES - n_half)
            if (
                shorten
                and math.isinf(tau_end)
                and HAS_DRAG
                and 0.0 < drop < _AVERAGED_DROP
                and drop <= drop_before  # a decay that slows (or holds its rate)
                and a < 0.5 * a_try
                and remaining > _AVERAGED_MIN_HALF_CYCLES
            ):
                # the rest of the sum from the averaged motion of these half cycles
                # (the exact sum's steps are the reference: fixed_steps > 0 never
                # takes it)
                a_try = a
                rest = averaged_tail(
                    a,
                    c,
                    ratio,
                    remaining,
                    _TAIL_TOLERANCE * c_start,
                    tables,
                    offsets,
                    tau_at,
                    c_at,
                    e_at,
                    fixed,
                )
                if math.isfinite(rest):
                    c_start += rest
                    break
    return finish(out, tau, j, c_end, c_start, tau_end)


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def grid(
    tau: NDArray,
    y0: NDArray,
    coef: NDArray,
    ratio: NDArray,
    yp0: float,
    tau_end: float,
    steps: int,
    creep_end: float = math.inf,
    error_weight: float = 1.0,
) -> tuple[NDArray, NDArray]:
    out = np.empty((y0.size, tau.size))
    status = np.zeros(y0.size, dtype=np.int64)
    if steps != 0:
        tables = nodes(0.0, abs(steps))
        offsets = np.zeros(1, dtype=np.int64)
    else:
        tables, offsets = _TABLES, _OFFSETS
    for p in range(y0.size):
        status[p] = one(
            tau,
            y0[p],
            coef[p],
            ratio[p],
            yp0,
            tau_end,
            steps,
            tables,
            offsets,
            out[p],
            creep_end,
            error_weight,
        )
    return out, status


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def turns(
    y0: float, c: NDArray, ratio: float, yp0: float, tau_max: float, max_count: int
) -> tuple[NDArray, NDArray]:
    """Turning times τ_n and positions Y_n of one trajectory (the initial state
    first when y'₀ = 0), until the motion stops, τ passes ``tau_max`` or
    ``max_count`` turning points; the last one is where the pin sticks, if it does."""
    tables, offsets = _TABLES, _OFFSETS
    size = LADDER[-1] + 1
    tau_at = np.empty(size)
    c_at = np.empty(size)
    e_at = np.empty((2, size))
    times = np.empty(max_count)
    where = np.empty(max_count)
    n = 0
    if yp0 == 0.0:
        sign = 1.0 if y0 >= 0.0 else -1.0
        a = abs(y0)
        mu = friction(a, c) if HAS_FRICTION else 0.0
        theta0 = 0.0
        r = a - mu
        times[0] = 0.0
        where[0] = y0
        n = 1
        if a <= ratio * mu or r <= 0.0:
            return times[:n], where[:n]
    else:
        sign = -1.0 if yp0 > 0.0 else 1.0
        ym = sign * y0
        vm = -abs(yp0)
        mu = friction(math.hypot(y0, yp0), c) if HAS_FRICTION else 0.0
        for _ in range(_START_ITERATIONS):
            if not HAS_FRICTION:
                break
            mu = friction(math.hypot(ym - mu, vm) + mu, c)
        r = math.hypot(ym - mu, vm)
        theta0 = math.atan2(-vm, ym - mu)
    t = 0.0
    while n < max_count and t <= tau_max and mu >= 0.0:
        if HAS_DRAG:
            k = choose_steps(r, c, 1.0)
            steps = LADDER[k]
            if theta0 == 0.0:
                table = tables[:, offsets[k] : offsets[k] + 2 * steps + 1]
            else:
                table = nodes(theta0, steps)
            r_end = half_cycle(table, r, mu, c, steps, tau_at, c_at, e_at)
            if not math.isfinite(r_end):
                break
            t += tau_at[steps]
        else:
            r_end = r  # an arc of the undamped motion
            t += math.pi - theta0
        y_turn = mu - r_end
        times[n] = t
        where[n] = sign * y_turn
        n += 1
        if y_turn >= 0.0:
            break
        a = -y_turn
        sign = -sign
        mu = friction(a, c) if HAS_FRICTION else 0.0
        if a <= ratio * mu or a - mu <= 0.0:
            break
        r = a - mu
        theta0 = 0.0
    return times[:n], where[:n]


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def half_cycle_end(a: float, c: NDArray, aux: tuple[NDArray, NDArray, NDArray]) -> float:
    """|Y| at the end of the half cycle that starts at rest at the turning point
    ``a`` > 0, ignoring static friction (NaN when the motion cannot leave ``a`` or
    the drag stops it before it turns); ``aux`` the ladder's tables, their offsets
    and a work array (4, LADDER[-1] + 1)."""
    tables, offsets, work = aux
    mu = friction(a, c) if HAS_FRICTION else 0.0
    r = a - mu
    if not (r > 0.0) or mu < 0.0:
        return math.nan
    if not HAS_DRAG:
        return r - mu  # an arc of the undamped motion
    k = choose_steps(r, c, 1.0)
    steps = LADDER[k]
    table = tables[:, offsets[k] : offsets[k] + 2 * steps + 1]
    r_end = half_cycle(table, r, mu, c, steps, work[0], work[1], work[2:4])
    if not math.isfinite(r_end):
        return math.nan
    return r_end - mu


@numba.njit(cache=True, error_model="numpy", fastmath=_FAST)
def swing_drops(coef: NDArray, swing: NDArray) -> NDArray:
    """The drop a_s - a_e of the half cycle whose swing ½(a_s + a_e) is each of
    ``swing`` (S,), for each coefficient row of ``coef`` (P, K): shape (P, S).

    a_s is found by the secant method on ½(a_s + a_e(a_s)) = A
    (:func:`~bayestribo.model.laws._core_shared.swing_ends`); NaN where no such half
    cycle exists."""
    size = LADDER[-1] + 1
    aux = (_TABLES, _OFFSETS, np.empty((4, size)))
    out = np.empty((coef.shape[0], swing.size))
    for p in range(coef.shape[0]):
        # each swing started from the ones solved before on the row (swing_guess)
        a1 = s1 = a2 = s2 = math.nan
        for j in range(swing.size):
            guess, slope = swing_guess(swing[j], a1, s1, a2, s2)
            a_s, a_e = swing_ends(swing[j], coef[p], aux, guess, slope)
            a2, s2, a1, s1 = a1, s1, swing[j], a_s
            out[p, j] = a_s - a_e
    return out
