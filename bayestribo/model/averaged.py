r"""Averaged (slowly varying amplitude) model of the free decay, Eq. 32-41.

Averaging Eq. 7 over one oscillation (Eq. 29-31) gives the amplitude equation
``a' = -ζa - 2μ_k/π`` (Eq. 32), solved by

.. math::  a(τ) = (a_0 + Γ) e^{-ζτ} - Γ, \qquad Γ = \frac{2μ_k}{πζ}   \quad (Eq. 34, 36)

with ``E = a²/2`` (Eq. 35), and the end of motion ``T_f = ln(Λ/Γ)/ζ``, ``Λ = a_0 + Γ``
(Eq. 38).

Correction to the paper: integrating Eq. 35 from τ to T_f gives Eq. 40 with the constant
``A = (Γ²/ζ)(3/4 - ½ ln(Γ/Λ))``; the printed Eq. 41 lacks the factor ½ on the
logarithm (the printed constant makes Π_app(T_f) ≠ 0). The tests check the corrected
constant against quadrature of Eq. 35.

The forms of Eq. 34-40 divide by ζ and lose all precision as ζ → 0 (pure Coulomb
friction) or overflow as μ_k → 0 (pure viscous damping). This module evaluates them
without cancellation: ``a(τ) = a_0 e^{-ζτ} - (2μ_k/π)(1 - e^{-ζτ})/ζ`` and, changing the
variable of integration from time to amplitude (``dθ = -da/(ζa + 2μ_k/π)``),

.. math::  Π_{app}(τ) = \int_0^{a(τ)} \frac{α^2/2}{ζα + 2μ_k/π}\, dα,

which has an elementary primitive evaluated with series where it cancels. Both limits
are then exact: ζ → 0 gives the linear amplitude decay ``a = a_0 - 2μ_kτ/π`` and
``Π = π a³/(12 μ_k)``; μ_k → 0 gives ``a = a_0 e^{-ζτ}``, ``Π = a²/(4ζ)`` and T_f = ∞.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.model._checks import all_within, as_finite, check_parameters
from bayestribo.model._special import expm1_ratio

__all__ = ["averaged_amplitude", "averaged_energy", "averaged_pi", "extinction_time"]

_PSI_SERIES = 1e-2


def _check(y0: ArrayLike, zeta: ArrayLike, mu_k: ArrayLike) -> tuple[NDArray, NDArray, NDArray]:
    try:
        a0, z, mk = (np.asarray(v, dtype=float) for v in (y0, zeta, mu_k))
    except (TypeError, ValueError):
        pass  # named below
    else:
        if all_within(a0, 0.0) and all_within(z, 0.0, 1.0) and all_within(mk, 0.0):
            return a0, z, mk
    a0 = as_finite("y0", y0)
    if np.any(a0 < 0.0):
        raise ValueError("y0 must be >= 0: it is the initial amplitude of the averaged model")
    z, mk, _ = check_parameters(zeta, mu_k)
    return a0, z, mk


def _times(name: str, value: ArrayLike) -> NDArray:
    """``value`` as a float array of times τ >= 0; ``ValueError`` naming ``name``
    otherwise."""
    try:
        t = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        pass  # named below
    else:
        if all_within(t, 0.0):
            return t
    t = as_finite(name, value)
    if np.any(t < 0.0):
        raise ValueError(f"{name} must be >= 0")
    return t


def _log1p_over(w: NDArray) -> NDArray:
    """log(1 + w)/w, 1 at w = 0."""
    safe = np.where(w == 0.0, 1.0, w)
    return np.where(w == 0.0, 1.0, np.log1p(safe) / safe)


def extinction_time(y0: ArrayLike, zeta: ArrayLike, mu_k: ArrayLike) -> NDArray:
    """Dimensionless end of motion of the averaged model, T_f (Eq. 38).

    ``T_f = ln(1 + πζa_0/(2μ_k))/ζ``: ``a_0π/(2μ_k)`` as ζ → 0 and ``inf`` for μ_k = 0.

    Parameters
    ----------
    y0 : array_like
        Initial amplitude a_0 = Y_0 >= 0 (Eq. 34).
    zeta, mu_k : array_like
        Equivalent viscous damping ζ in [0, 1) and kinetic friction μ_k >= 0.

    Returns
    -------
    ndarray
        T_f, broadcast over the arguments.
    """
    a0, z, mk = _check(y0, zeta, mu_k)
    c = 2.0 * mk / np.pi
    safe_c = np.where(c > 0.0, c, 1.0)
    w = z * a0 / safe_c
    with np.errstate(divide="ignore"):
        tf = a0 / safe_c * _log1p_over(w)
    return np.where(c > 0.0, tf, np.where(a0 > 0.0, np.inf, 0.0))


def _amplitude(tau: NDArray, a0: NDArray, z: NDArray, mk: NDArray) -> NDArray:
    a = a0 * np.exp(-z * tau) - (2.0 * mk / np.pi) * expm1_ratio(z, tau)
    return np.maximum(a, 0.0)


def averaged_amplitude(tau: ArrayLike, y0: ArrayLike, zeta: ArrayLike, mu_k: ArrayLike) -> NDArray:
    """Averaged amplitude a(τ) (Eq. 34), zero from the end of motion T_f on.

    Parameters
    ----------
    tau : array_like
        Dimensionless time τ >= 0 since the start of the analysed decay.
    y0, zeta, mu_k : array_like
        Initial amplitude a_0 >= 0, ζ in [0, 1), μ_k >= 0.
    """
    a0, z, mk = _check(y0, zeta, mu_k)
    t = as_finite("tau", tau)
    if np.any(t < 0.0):
        raise ValueError("tau must be >= 0")
    return _amplitude(t, a0, z, mk)


def averaged_energy(tau: ArrayLike, y0: ArrayLike, zeta: ArrayLike, mu_k: ArrayLike) -> NDArray:
    """Averaged energy decay E(τ) = a(τ)²/2 (Eq. 35); arguments as :func:`averaged_amplitude`."""
    a = averaged_amplitude(tau, y0, zeta, mu_k)
    return 0.5 * a * a


def _pi_of_amplitude(a: NDArray, z: NDArray, mk: NDArray) -> NDArray:
    """∫_0^a (α²/2)/(ζα + c) dα with c = 2μ_k/π, stable for every ζ, μ_k >= 0."""
    c = 2.0 * mk / np.pi
    # Branches not selected may overflow for extreme ratios of ζ to μ_k.
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        w = np.where(c > 0.0, z * a / np.where(c > 0.0, c, 1.0), np.inf)
        # w <= 1: a³ ψ(w)/(2c), ψ(w) = (ln(1+w) - w + w²/2)/w³ = Σ (-w)^k/(k+3).
        ws = np.where(w <= 1.0, w, 0.0)
        series = np.zeros_like(ws)
        for k in range(8, -1, -1):  # Horner form of Σ_{k<9} (-w)^k/(k+3)
            series = 1.0 / (k + 3.0) - ws * series
        direct = (np.log1p(ws) - ws + 0.5 * ws * ws) / np.where(ws > 0.0, ws**3, 1.0)
        psi = np.where(ws < _PSI_SERIES, series, direct)
        small = a**3 * psi / (2.0 * np.where(c > 0.0, c, 1.0))
        # w > 1: a²/(2ζ) χ(w), χ(w) = 1/2 - 1/w + ln(1+w)/w² (1/2 as w → ∞).
        wl = np.where(w > 1.0, w, 2.0)
        inv = np.where(np.isfinite(wl), 1.0 / wl, 0.0)
        chi = 0.5 - inv + np.where(np.isfinite(wl), np.log1p(wl) * inv * inv, 0.0)
        large = a * a * chi / (2.0 * np.where(z > 0.0, z, 1.0))
        out = np.where(w <= 1.0, small, large)
        # ζ = μ_k = 0: no dissipation, the integral diverges.
        return np.where((z == 0.0) & (c == 0.0), np.where(a > 0.0, np.inf, 0.0), out)


def averaged_pi(
    tau: ArrayLike,
    y0: ArrayLike,
    zeta: ArrayLike,
    mu_k: ArrayLike,
    tau_end: ArrayLike | None = None,
) -> NDArray:
    """Approximate retrograde energy integral Π_app(τ) (Eq. 40 with corrected Eq. 41).

    Parameters
    ----------
    tau : array_like
        Dimensionless time τ >= 0 since the start of the analysed decay.
    y0 : array_like
        Initial amplitude a_0 = Y_0 >= 0.
    zeta, mu_k : array_like
        ζ in [0, 1) and μ_k >= 0.
    tau_end : array_like, optional
        End of the record: integrate to ``min(T_f, tau_end)`` instead of T_f.

    Returns
    -------
    ndarray
        Π_app(τ) = ∫_τ^{T} a(θ)²/2 dθ, 0 at and after T.
    """
    from bayestribo.model._averaged_ufuncs import averaged_pi_ufunc, averaged_pi_until

    a0, z, mk = _check(y0, zeta, mu_k)
    t = _times("tau", tau)
    # One compiled pass over the broadcast arguments (the same formulas as
    # _pi_of_amplitude and _amplitude here, which stay the numpy reference).
    if tau_end is None:
        return np.asarray(averaged_pi_ufunc(t, a0, z, mk), dtype=float)
    te = _times("tau_end", tau_end)
    return np.asarray(averaged_pi_until(t, te, a0, z, mk), dtype=float)
