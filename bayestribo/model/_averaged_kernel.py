"""Compiled scalar forms of the averaged model (Eq. 34 and 40 with the corrected Eq. 41).

One implementation of the averaged amplitude and of Π_app as a function of amplitude,
in numba, called element by element: by :func:`bayestribo.model.averaged.averaged_pi`
through the ufuncs of :mod:`bayestribo.model._averaged_ufuncs` (one pass over the
broadcast arguments, no temporaries), and by the fused log posterior
(:mod:`bayestribo.inference.fused`). The formulas and their
series are those of :mod:`bayestribo.model.averaged`'s module notes; the tests check
them against quadrature of Eq. 35 and the limits ζ → 0 and μ_k → 0.
"""

from __future__ import annotations

import math

import numba

__all__ = ["averaged_amplitude", "pi_of_amplitude"]

#: Arguments below this are treated as 0 (as :data:`bayestribo.model._special.TINY`).
_TINY = 1e-100
#: Below this w = ζa/c, ψ(w) is summed as its series (cancellation in the direct form).
PSI_SERIES = 1e-2
#: The one floating-point liberty taken: a product and a sum fused into one rounding
#: (FMA) where the processor has it, which takes a tenth off the averaged Π's time; no
#: other (NaN, infinities, signed zeros and the order of operations are kept).
_CONTRACT = {"contract"}


@numba.njit(cache=True, error_model="numpy", fastmath=_CONTRACT)
def _expm1_ratio(a: float, length: float) -> float:
    """(1 - exp(-a L))/a, L at a = 0."""
    if abs(a) < _TINY:
        return length
    return -math.expm1(-a * length) / a


@numba.njit(cache=True, error_model="numpy", fastmath=_CONTRACT)
def averaged_amplitude(t: float, a0: float, z: float, mk: float) -> float:
    """a(τ) of Eq. 34, zero after the end of motion."""
    if abs(z) < _TINY:
        return max(a0 - (2.0 * mk / math.pi) * t, 0.0)
    # One transcendental call for both terms: e^{-ζτ} where 1 - e^{-ζτ} does not
    # cancel, e^{-ζτ} - 1 where it would (1 + that is then at least 0.6, exact enough).
    x = z * t
    if x > 0.5:
        e = math.exp(-x)
        a = a0 * e - (2.0 * mk / math.pi) * (1.0 - e) / z
    else:
        e = math.expm1(-x)
        a = a0 * (1.0 + e) + (2.0 * mk / math.pi) * e / z
    return max(a, 0.0)


@numba.njit(cache=True, error_model="numpy", fastmath=_CONTRACT)
def pi_of_amplitude(a: float, z: float, mk: float) -> float:
    """∫_0^a (α²/2)/(ζα + 2μ_k/π) dα, stable for every ζ, μ_k >= 0 (inf for ζ = μ_k = 0)."""
    c = 2.0 * mk / math.pi
    if z == 0.0 and c == 0.0:
        return math.inf if a > 0.0 else 0.0
    w = z * a / c if c > 0.0 else math.inf
    if w <= 1.0:
        # a³ ψ(w)/(2c), ψ(w) = (ln(1+w) - w + w²/2)/w³ = Σ (-w)^k/(k+3)
        if w < PSI_SERIES:
            psi = 0.0
            for k in range(8, -1, -1):
                psi = 1.0 / (k + 3.0) - w * psi
        else:
            psi = (math.log1p(w) - w + 0.5 * w * w) / (w * w * w if w > 0.0 else 1.0)
        return a * a * a * psi / (2.0 * (c if c > 0.0 else 1.0))
    # a²/(2ζ) χ(w), χ(w) = 1/2 - 1/w + ln(1+w)/w² (1/2 as w → ∞)
    wl = w if w > 1.0 else 2.0  # a NaN w takes the numpy form's placeholder
    finite = math.isfinite(wl)
    inv = 1.0 / wl if finite else 0.0
    chi = 0.5 - inv + (math.log1p(wl) * inv * inv if finite else 0.0)
    return a * a * chi / (2.0 * (z if z > 0.0 else 1.0))
