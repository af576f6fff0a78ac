r"""Exact piecewise free response of an oscillator with viscous damping and Coulomb friction.

Rigaud et al. (2010), Eq. 12-20 with the stick rule of Eq. 5/8. In dimensionless form
(Eq. 7) the motion obeys ``y'' + 2ζy' + y = -μ_k sgn(y')`` while the pin slides. Between
two turning points (``y' = 0``) the sign of ``y'`` is fixed, so each half cycle is a
damped linear oscillation about the centre ``c_n = μ_k sgn(Y_n)``:

.. math::

    y(τ) = c_n + (Y_n - c_n)\, f(s), \qquad
    y'(τ) = -\frac{Y_n - c_n}{ω} e^{-ζs}\sin ωs, \qquad s = τ - τ_n,

with ``f(s) = e^{-ζs}(\cos ωs + β\sin ωs)``, ``ω = √(1-ζ²)`` (Eq. 13), ``β = ζ/ω``
(Eq. 14), ``τ_{n+1} = τ_n + π/ω`` (Eq. 16-17, verified). The motion stops at the first
turning point with ``|Y_n| ≤ μ_s`` (Eq. 8) and the pin stays there.

Closed forms used here (derived for this module and checked in the tests against
``solve_ivp`` and quadrature):

* Amplitude about the centre, ``A_n = |Y_n| - μ_k``, obeys ``A_{n+1} = q A_n - 2μ_k``
  with ``q = e^{-βπ}``; this is Eq. 20 rewritten, so
  ``A_n = q^n A_0 - 2μ_k D_n`` with ``D_n = Σ_{i<n} q^i``. The number of moving half
  cycles M is the first n with ``A_n ≤ μ_s - μ_k``, found in closed form from the
  logarithm of the geometric sequence (no loop over half cycles).
* Energy in a half cycle, ``E = ½(y² + y'²) = ½c² + c u + ½(u² + u'²)`` with
  ``u = y - c``; its integral over the rest of a half cycle is elementary (``P1``,
  ``P2`` below), and the sum of whole half cycles is a sum of geometric and
  arithmetico-geometric series in ``q``. So Π(τ) costs O(1) per point, whatever the
  number of half cycles, and never uses a time grid.
* An initial state with ``y'_0 ≠ 0`` lies inside a half cycle that began at a virtual
  turning point a time ``σ₀`` earlier; that turning point is found in closed form from
  the phase of the damped oscillation, and the first (partial) half cycle is then
  handled by the same formulas.

All functions broadcast their arguments with numpy rules: parameters of shape ``(P, 1)``
and ``tau`` of shape ``(T,)`` give ``(P, T)`` results, which is how an ensemble sampler
evaluates many walkers at once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.model._checks import as_finite, check_parameters
from bayestribo.model._chunks import over_tau_blocks
from bayestribo.model._special import TINY, expm1_ratio, geometric_sum, gminus, log1p_ratio

__all__ = [
    "exact_energy",
    "exact_pi",
    "exact_response",
    "rest_position",
    "stop_time",
    "turning_points",
]

# Below this value of x·L (viscous decay over the summed half cycles) the sums are
# taken from series: the closed form of Σ D_i² loses about 3ε/(xL) to cancellation,
# and its first-order Taylor expansion in x has relative error O((xL)²).
_SERIES_XL = 1e-6
# Below this value of x·L, exp(-xL) - 1 + xL is taken from its Taylor series.
_GMINUS_SERIES = 1e-3
# Below this x = βπ, the sums over half cycles take their ζ = 0 (polynomial) form.
_NEGLIGIBLE_X = TINY


@dataclass(frozen=True)
class _Trajectory:
    """Per-parameter-set constants of the piecewise solution (arrays of one shape)."""

    zeta: NDArray
    mu_k: NDArray
    omega: NDArray
    beta: NDArray
    x: NDArray  # βπ: logarithmic decrement of one half cycle
    q: NDArray  # e^{-βπ}
    half: NDArray  # π/ω: duration of a half cycle
    sigma0: NDArray  # time of the initial state after the first (maybe virtual) turning point
    a0: NDArray  # amplitude about the centre in the first half cycle
    sign0: NDArray  # sign of the first turning point Y_0
    n_moving: NDArray  # number M of half cycles before the stop (inf: never stops)
    y_rest: NDArray  # position where the pin sticks (nan if it never does)

    @property
    def tau_stop(self) -> NDArray:
        return self.n_moving * self.half - self.sigma0

    def amplitude(self, n: NDArray) -> NDArray:
        """A_n = q^n A_0 - 2 μ_k D_n (Eq. 20 iterated)."""
        return _amplitude(n, self.a0, self.mu_k, self.x)


def _amplitude(n: NDArray, a0: NDArray, mu_k: NDArray, x: NDArray) -> NDArray:
    """Amplitude about the centre after n half cycles, A_n = q^n A_0 - 2 μ_k D_n."""
    return a0 * np.exp(-n * x) - 2.0 * mu_k * geometric_sum(n, x)


def _start(
    y0: NDArray, yp0: NDArray, z: NDArray, mk: NDArray, omega: NDArray
) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """Offset σ₀, amplitude A_0, sign of Y_0 and first stoppable index of the start."""
    moving = yp0 != 0.0
    if not np.any(moving):
        # Start at a turning point (y'_0 = 0): Eq. 15.
        zero = np.zeros_like(y0)
        return zero, np.abs(y0) - mk, np.where(y0 >= 0.0, 1.0, -1.0), zero
    # Start inside a half cycle: locate its virtual turning point σ₀ earlier.
    sv = np.sign(yp0)
    r = y0 + mk * sv + z * yp0  # displacement about the centre c = -μ_k sgn(y'_0), plus ζy'_0
    sigma_mv = np.arctan2(omega * np.abs(yp0), -sv * r) / omega
    a_mv = np.hypot(omega * yp0, r) * np.exp(z * sigma_mv)
    if np.all(moving):
        return sigma_mv, a_mv, -sv, np.ones_like(y0)
    return (
        np.where(moving, sigma_mv, 0.0),
        np.where(moving, a_mv, np.abs(y0) - mk),
        np.where(moving, -sv, np.where(y0 >= 0.0, 1.0, -1.0)),
        np.where(moving, 1.0, 0.0),
    )


def _trajectory(
    y0: ArrayLike,
    zeta: ArrayLike,
    mu_k: ArrayLike,
    mu_s: ArrayLike,
    yp0: ArrayLike,
    validate: bool = True,
) -> _Trajectory:
    if validate:
        y0 = as_finite("y0", y0)
        yp0 = as_finite("yp0", yp0)
        z, mk, ms = check_parameters(zeta, mu_k, mu_s)
    else:
        y0, yp0, z, mk, ms = (np.asarray(a, dtype=float) for a in (y0, yp0, zeta, mu_k, mu_s))
    y0, yp0, z, mk, ms = np.broadcast_arrays(y0, yp0, z, mk, ms)

    omega = np.sqrt((1.0 - z) * (1.0 + z))
    beta = z / omega
    x = np.pi * beta
    q = np.exp(-x)
    half = np.pi / omega
    sigma0, a0, sign0, n_min = _start(y0, yp0, z, mk, omega)

    # First n >= n_min with A_n <= μ_s - μ_k: solve q^n (A_0 + r) = δ + r, r = 2μ_k/(1-q).
    delta = ms - mk
    one_m_q = -np.expm1(-x)
    den = a0 * one_m_q + 2.0 * mk
    excess = a0 - delta
    never = (mk == 0.0) & (excess > 0.0) & ((x < TINY) | (delta == 0.0))
    ok = (excess > 0.0) & ~never
    safe_den = np.where(ok, den, 1.0)
    # without friction w = excess/A₀ and excess/den = w/(1 - q), exactly: written so, a
    # tiny amplitude times a tiny 1 - q (den below the smallest double) is not 0/0
    viscous = mk == 0.0
    safe_a0 = np.where(ok & viscous, a0, 1.0)
    w = np.where(ok, np.where(viscous, excess / safe_a0, excess * one_m_q / safe_den), 0.0)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        per_den = np.where(viscous, w / np.where(ok, one_m_q, 1.0), excess / safe_den)
        n_star = np.where(ok, per_den * expm1_ratio(x, 1.0) * log1p_ratio(w), 0.0)
    n_moving = np.maximum(n_min, np.ceil(n_star))

    # One correction step either way absorbs rounding in the logarithm.
    def amp(n: NDArray) -> NDArray:
        return _amplitude(n, a0, mk, x)

    # n* can be infinite (friction below double precision): those rows keep it.
    with np.errstate(invalid="ignore"):
        down = ok & (n_moving - 1.0 >= n_min) & (amp(n_moving - 1.0) <= delta)
        n_moving = n_moving - down
        up = ok & (amp(n_moving) > delta)
    n_moving = np.where(never, np.inf, n_moving + up)

    last = np.where(np.isfinite(n_moving), np.maximum(n_moving - 1.0, 0.0), 0.0)
    sign_last = sign0 * _parity_sign(last)
    y_rest = np.where(n_moving == 0.0, y0, sign_last * (mk - amp(last) * q))
    y_rest = np.where(np.isfinite(n_moving), y_rest, np.nan)
    return _Trajectory(z, mk, omega, beta, x, q, half, sigma0, a0, sign0, n_moving, y_rest)


def _sincos_half_cycle(theta: NDArray) -> tuple[NDArray, NDArray]:
    """sin θ and cos θ for θ in [0, π] from one tangent of the half angle.

    ``tan`` is several times cheaper than ``sin`` plus ``cos`` in numpy, and the
    half-angle forms keep an absolute error of a few ulps over the half cycle.
    """
    t = np.tan(0.5 * theta)
    inv = 1.0 / (1.0 + t * t)
    return 2.0 * t * inv, (1.0 - t * t) * inv


def _parity_sign(n: NDArray) -> NDArray:
    """(-1)^n for integer-valued float n."""
    return 1.0 - 2.0 * (n - 2.0 * np.floor(0.5 * n))


def _locate(tr: _Trajectory, tau: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """Half-cycle index n, local time s and 'still moving' mask for each τ."""
    n = np.floor((tau + tr.sigma0) / tr.half)
    moving = n < tr.n_moving
    n = np.where(moving, n, 0.0)
    # After the stop the local time is irrelevant; 0 keeps trigonometry in range.
    s = np.where(moving, tau + tr.sigma0 - n * tr.half, 0.0)
    return n, s, moving


def _check_tau(tau: ArrayLike, name: str = "tau") -> NDArray:
    t = as_finite(name, tau)
    if np.any(t < 0.0):
        raise ValueError(f"{name} must be >= 0 (dimensionless time since the initial state)")
    return t


def exact_response(
    tau: ArrayLike,
    y0: ArrayLike,
    zeta: ArrayLike,
    mu_k: ArrayLike,
    mu_s: ArrayLike,
    yp0: ArrayLike = 0.0,
    *,
    validate: bool = True,
) -> tuple[NDArray, NDArray]:
    """Exact dimensionless displacement and velocity, with sticking (Eq. 16-17, 8).

    Parameters
    ----------
    tau : array_like
        Dimensionless time τ = Ωt since the initial state, ``>= 0``.
    y0 : array_like
        Initial dimensionless displacement y(0) = kx(0)/N.
    zeta : array_like
        Equivalent viscous damping ζ, ``0 <= ζ < 1``.
    mu_k : array_like
        Kinetic friction coefficient μ_k ``>= 0`` (or friction displacement in the
        length unit of y).
    mu_s : array_like
        Static friction coefficient μ_s ``>= μ_k``: the motion stops at the first
        turning point with ``|y| <= μ_s``.
    yp0 : array_like, optional
        Initial dimensionless velocity y'(0); 0 starts at a turning point (Eq. 15).
    validate : bool, optional
        Check the arguments (default). A caller that has checked them already (a
        sampler whose priors keep the parameters in range) may skip the checks.

    Returns
    -------
    y, yp : ndarray
        y(τ) and y'(τ), broadcast over all arguments. After the stop, y stays at the
        rest position and y' = 0.

    Raises
    ------
    ValueError
        For negative τ, ζ outside [0, 1), μ_k < 0, μ_s < μ_k or non-finite values.
    """
    tr = _trajectory(y0, zeta, mu_k, mu_s, yp0, validate)
    t = _check_tau(tau) if validate else np.asarray(tau, dtype=float)
    return over_tau_blocks(lambda block: _response(tr, block), t, tr.zeta.shape)


def _response(tr: _Trajectory, t: NDArray) -> tuple[NDArray, NDArray]:
    n, s, moving = _locate(tr, t)
    amp = tr.amplitude(n)
    sign_n = tr.sign0 * _parity_sign(n)
    decay = np.exp(-tr.zeta * s)
    sin, cos = _sincos_half_cycle(tr.omega * s)
    y = sign_n * (tr.mu_k + amp * decay * (cos + tr.beta * sin))
    yp = -sign_n * amp / tr.omega * decay * sin
    return np.where(moving, y, tr.y_rest), np.where(moving, yp, 0.0)


def exact_energy(
    tau: ArrayLike,
    y0: ArrayLike,
    zeta: ArrayLike,
    mu_k: ArrayLike,
    mu_s: ArrayLike,
    yp0: ArrayLike = 0.0,
) -> NDArray:
    """Exact energy E(τ) = (y² + y'²)/2 (Eq. 26); arguments as :func:`exact_response`."""
    y, yp = exact_response(tau, y0, zeta, mu_k, mu_s, yp0)
    return 0.5 * (y * y + yp * yp)


def _partial_integrals(tr: _Trajectory, s: NDArray) -> tuple[NDArray, NDArray]:
    """P1(s) = ∫_s^{π/ω} f and P2(s) = ∫_s^{π/ω} (f² + f'²) over one half cycle."""
    z, om, be = tr.zeta, tr.omega, tr.beta
    decay = np.exp(-z * s)
    sin, cos = _sincos_half_cycle(om * s)
    # ∫ f = -(f' + 2ζ f) because f'' + 2ζ f' + f = 0; f(π/ω) = -q, f'(π/ω) = 0.
    p1 = 2.0 * z * tr.q + decay * (2.0 * z * (cos + be * sin) - sin / om)
    # f² + f'² = e^{-2ζs} (1 + β² + β sin 2ωs - β² cos 2ωs).
    sin2, cos2 = 2.0 * sin * cos, cos * cos - sin * sin
    g_s = 0.5 * z * decay**2 * ((be * be - 1.0) * cos2 - 2.0 * be * sin2)
    g_end = 0.5 * z * tr.q**2 * (be * be - 1.0)
    p2 = (1.0 + be * be) * decay**2 * expm1_ratio(2.0 * z, tr.half - s) + g_end - g_s
    return p1, p2


def _partial_half_cycle(tr: _Trajectory, s: NDArray, amp: NDArray) -> NDArray:
    """∫ E from local time s to the end of a half cycle of amplitude ``amp``."""
    p1, p2 = _partial_integrals(tr, s)
    mk = tr.mu_k
    return 0.5 * mk * mk * (tr.half - s) + mk * amp * p1 + 0.5 * amp * amp * p2


def _whole_half_cycles(tr: _Trajectory, length: NDArray, amp: NDArray) -> NDArray:
    """Σ of ∫E over ``length`` whole half cycles starting with amplitude ``amp``.

    With A_{j+i} = q^i A_j - 2μ_k D_i the sums over i < L reduce to
    D_L = Σ q^i, Σ q^{2i}, E1 = Σ D_i, E2 = Σ q^i D_i and E3 = Σ D_i². The closed forms
    below hold for ζ > 0 and keep full precision while xL is not tiny (x = βπ); the
    few elements where they would cancel (xL < 1e-3, or ζ = 0 exactly, where the sums
    are polynomials in L) are recomputed with series.
    """
    x, q, mk, z, be = tr.x, tr.q, tr.mu_k, tr.zeta, tr.beta
    f1 = 2.0 * z * (1.0 + q)
    f2 = (1.0 + be * be) * expm1_ratio(2.0 * z, tr.half) + 0.5 * z * (be * be - 1.0) * (q * q - 1.0)

    finite = np.isfinite(length)
    n = np.where(finite, length, 0.0)
    xs = np.where(x >= _NEGLIGIBLE_X, x, 1.0)
    one_m_q = -np.expm1(-xs)
    nx = n * xs
    em = np.expm1(-nx)  # q^L - 1
    d1 = -em / one_m_q
    d2 = d1 * (2.0 + em) / (1.0 + q)  # Σ q^{2i} = D_L (1 + q^L)/(1 + q)
    e1 = (em + nx - n * gminus(xs)) / one_m_q**2  # (g(Lx) - L g(x))/(1-q)²
    e2 = d1 * (d1 - 1.0) / (1.0 + q)
    e3 = (e1 - e2) / one_m_q

    # x² underflows below ~1e-154: there ζ has no effect in double precision, and the
    # ζ = 0 polynomials are used.
    negligible = x < _NEGLIGIBLE_X
    # L = 0 is exact in the closed forms (every sum vanishes), and so is L = 1 when
    # gminus(x) is not a series (the same operations cancel exactly).
    special = np.broadcast_to(negligible, n.shape) | ((nx < _GMINUS_SERIES) & (n >= 1.0))
    if np.any(special):
        xb = np.broadcast_to(x, n.shape)[special]
        qb = np.broadcast_to(q, n.shape)[special]
        nb = n[special]
        d1, d2, e1, e2, e3 = (np.array(np.broadcast_to(a, n.shape)) for a in (d1, d2, e1, e2, e3))
        d1[special] = geometric_sum(nb, xb)
        d2[special] = geometric_sum(nb, 2.0 * xb)
        e1[special] = np.where(
            xb >= _NEGLIGIBLE_X,
            (gminus(nb * xb) - nb * gminus(xb))
            / np.where(xb >= _NEGLIGIBLE_X, -np.expm1(-xb), 1.0) ** 2,
            0.5 * nb * (nb - 1.0),
        )
        e2[special] = d1[special] * (d1[special] - 1.0) / (1.0 + qb)
        # First order in x of Σ D_i², D_i ≈ i - x i(i-1)/2: relative error O((xL)²).
        s2 = (nb - 1.0) * nb * (2.0 * nb - 1.0) / 6.0
        s3 = (0.5 * nb * (nb - 1.0)) ** 2
        closed = (e1[special] - e2[special]) / np.where(xb >= _NEGLIGIBLE_X, -np.expm1(-xb), 1.0)
        e3[special] = np.where(nb * xb < _SERIES_XL, s2 - xb * (s3 - s2), closed)

    sum_a = amp * d1 - 2.0 * mk * e1
    sum_a2 = amp * amp * d2 - 4.0 * mk * amp * e2 + 4.0 * mk * mk * e3
    total = 0.5 * mk * mk * tr.half * n + mk * f1 * sum_a + 0.5 * f2 * sum_a2
    if np.all(finite):
        return total
    # Endless motion only happens without friction: a geometric series in q².
    with np.errstate(divide="ignore"):
        endless = np.where(x >= _NEGLIGIBLE_X, 0.5 * f2 * amp * amp / -np.expm1(-2.0 * xs), np.inf)
    return np.where(finite, total, endless)


def exact_pi(
    tau: ArrayLike,
    y0: ArrayLike,
    zeta: ArrayLike,
    mu_k: ArrayLike,
    mu_s: ArrayLike,
    yp0: ArrayLike = 0.0,
    tau_end: ArrayLike | None = None,
    *,
    validate: bool = True,
    backend: str = "compiled",
) -> NDArray:
    """Retrograde integral of the exact energy, Π(τ) = ∫_τ^{T} E(θ) dθ (Eq. 39).

    Parameters
    ----------
    tau, y0, zeta, mu_k, mu_s, yp0 : array_like
        As in :func:`exact_response`.
    tau_end : array_like, optional
        End of the record. The integral runs to ``T = min(stop, tau_end)``, the end of
        motion or of the record, whichever comes first; the energy of the pin at rest
        after the stop is never counted. ``None``: to the end of motion.
    validate : bool, optional
        Check the arguments (default); see :func:`exact_response`.
    backend : {"compiled", "numpy"}, optional
        The compiled kernel (:mod:`bayestribo.model._kernel`, the default: the same
        closed forms, one trajectory per row) or this module's numpy implementation,
        the reference the tests hold the kernel to (1e-12).

    Returns
    -------
    ndarray
        Π(τ), 0 for τ at or after T; ``inf`` only for motion that never ends
        (ζ = μ_k = 0) without ``tau_end``.

    Notes
    -----
    Each half cycle's integral is elementary and the sum over whole half cycles is a
    closed-form series (see the module notes), so the cost does not grow with the
    number of oscillations.
    """
    if backend not in ("compiled", "numpy"):
        raise ValueError(f"backend must be 'compiled' or 'numpy', got {backend!r}")
    if backend == "compiled":
        from bayestribo.model._kernel import exact_pi_rows

        if validate:
            y0 = as_finite("y0", y0)
            yp0 = as_finite("yp0", yp0)
            zeta, mu_k, mu_s = check_parameters(zeta, mu_k, mu_s)
            tau = _check_tau(tau)
            if tau_end is not None:
                tau_end = _check_tau(tau_end, "tau_end")
        end = np.inf if tau_end is None else tau_end
        return exact_pi_rows(tau, y0, zeta, mu_k, mu_s, yp0, end)
    tr = _trajectory(y0, zeta, mu_k, mu_s, yp0, validate)
    t = _check_tau(tau) if validate else np.asarray(tau, dtype=float)
    if tau_end is None:
        upper, tail, end = tr.n_moving, np.zeros(()), tr.tau_stop
    else:
        te = _check_tau(tau_end, "tau_end") if validate else np.asarray(tau_end, dtype=float)
        n_e, s_e, trunc = _locate(tr, te)
        # Whole half cycles run up to the one holding tau_end, minus its unused part.
        upper = np.where(trunc, n_e + 1.0, tr.n_moving)
        tail = np.where(trunc, _partial_half_cycle(tr, s_e, tr.amplitude(n_e)), 0.0)
        end = np.minimum(tr.tau_stop, te)
    shape = np.broadcast_shapes(tr.zeta.shape, np.shape(upper), np.shape(end))
    return over_tau_blocks(lambda block: _pi(tr, block, upper, tail, end), t, shape)


def _pi(tr: _Trajectory, t: NDArray, upper: NDArray, tail: NDArray, end: NDArray) -> NDArray:
    n, s, moving = _locate(tr, t)
    amp = tr.amplitude(n)
    head = _partial_half_cycle(tr, s, amp)
    amp_next = tr.q * amp - 2.0 * tr.mu_k
    rest = _whole_half_cycles(tr, np.maximum(upper - n - 1.0, 0.0), amp_next)
    return np.where(moving & (t < end), head + rest - tail, 0.0)


def stop_time(
    y0: ArrayLike, zeta: ArrayLike, mu_k: ArrayLike, mu_s: ArrayLike, yp0: ArrayLike = 0.0
) -> NDArray:
    """Dimensionless time at which the motion stops (``inf`` if it never does)."""
    return _trajectory(y0, zeta, mu_k, mu_s, yp0).tau_stop


def rest_position(
    y0: ArrayLike, zeta: ArrayLike, mu_k: ArrayLike, mu_s: ArrayLike, yp0: ArrayLike = 0.0
) -> NDArray:
    """Dimensionless position where the pin sticks (``nan`` if it never stops)."""
    return _trajectory(y0, zeta, mu_k, mu_s, yp0).y_rest


def turning_points(
    y0: float,
    zeta: float,
    mu_k: float,
    mu_s: float,
    yp0: float = 0.0,
    max_count: int | None = None,
) -> tuple[NDArray, NDArray]:
    """Times and positions of the turning points (y' = 0) of one trajectory (Eq. 20).

    Parameters
    ----------
    y0, zeta, mu_k, mu_s, yp0 : float
        Scalar parameters, as in :func:`exact_response`.
    max_count : int, optional
        Return at most this many turning points. Required when the motion never stops
        (ζ = μ_k = 0, or μ_k = μ_s = 0).

    Returns
    -------
    tau_n, Y_n : ndarray
        Turning times (τ >= 0; the initial state is included when y'_0 = 0) and
        positions; the last one is where the pin sticks, unless ``max_count`` cut the
        sequence first.
    """
    for name, val in (("y0", y0), ("zeta", zeta), ("mu_k", mu_k), ("mu_s", mu_s), ("yp0", yp0)):
        if np.ndim(val) != 0:
            raise ValueError(
                f"{name} must be a scalar for turning_points, got shape {np.shape(val)}"
            )
    tr = _trajectory(y0, zeta, mu_k, mu_s, yp0)
    m = float(tr.n_moving)
    first = 1 if yp0 != 0.0 else 0
    if not np.isfinite(m) and max_count is None:
        raise ValueError("the motion never stops for these parameters: pass max_count")
    last = m if max_count is None else min(m, first + int(max_count) - 1)
    n = np.arange(first, int(last) + 1, dtype=float)
    tau_n = n * tr.half - tr.sigma0
    sign_n = tr.sign0 * _parity_sign(n)
    y_n = sign_n * (tr.amplitude(n) + tr.mu_k)
    if np.isfinite(m) and n.size and n[-1] == m:
        y_n[-1] = tr.y_rest
    return tau_n, y_n
