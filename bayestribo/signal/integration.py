"""The displacement of a velocity-only record, integrated as an oscillator's.

The trapezoidal rule integrates an oscillation at ω with the gain (ωh/2)cot(ωh/2)
(0.967 at 10 samples a period), which can be divided out at one frequency, but not
the rest of its error: a damped oscillation is not a sinusoid, and at each turning
point dry friction puts a kink in the velocity (its slope jumps by 2μ_kN/m) that the
rule smooths over. At 10 samples a period these leave the displacement off by about
1e-3 of the swing, an error of the energy hundreds of times the noise of a
vibrometer-grade velocity.

Between turning points the velocity of viscous damping and Coulomb friction is a
damped oscillation, ``v = Re(c e^{st})`` with one pole s = ω(-ζ + i√(1-ζ²)) for the
whole record, and three successive samples obey the recurrence
``v_{n+1} = 2e^{σh}cos(ω_d h) v_n - e^{2σh} v_{n-1}`` (σ = Re s, ω_d = Im s):
:func:`oscillation_pole` fits it by least squares to every triplet of samples that
does not straddle a turning point (a linear prediction, as in Prony's method), so the
pole comes from the velocity itself. :func:`integrate_oscillation` then integrates
each step with the two-point rule exact for e^{st} and e^{s̄t}, ``∫v = a v_n + b
v_{n+1}``, and splits a step where the velocity changes sign at its zero, found from
the damped oscillation through the two samples on each side: each side's piece is
integrated exactly, the kink falls between them. For the package's model the
displacement is then exact to rounding (1e-11 of the swing at 10 samples a period,
noise-free); for a nonlinear drag it is exact for the pole that fits the record best.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "MIN_TRIPLETS",
    "integrate_oscillation",
    "oscillation_energy",
    "oscillation_pole",
    "step_rule",
]

#: Triplets of samples off the turning points that the pole's fit needs.
MIN_TRIPLETS = 10
#: Fits of the pole, each leaving out the triplets whose prediction misses by more
#: than this many times the median miss of the last.
_PASSES, _OUTLIER = 3, 10.0


def step_rule(s: complex, h: float) -> tuple[float, float]:
    """Weights (a, b) of ``∫_0^h v = a v(0) + b v(h)``, exact for v = e^{st} and e^{s̄t}.

    Parameters
    ----------
    s : complex
        The pole [1/s] (Im s > 0, Im s · h not a multiple of π).
    h : float
        The step [s].

    Returns
    -------
    (float, float)
        a and b [s]; both h/2 (the trapezoidal rule) in the limit s h → 0.

    Examples
    --------
    >>> a, b = step_rule(1j, 0.1)
    >>> round(a, 6), round(b, 6)
    (0.049958, 0.049958)
    """
    z = complex(np.exp(s * h))
    whole = (z - 1.0) / s
    b = whole.imag / z.imag
    return whole.real - b * z.real, b


def oscillation_pole(t: ArrayLike, v: ArrayLike) -> complex | None:
    """The pole s = σ + iω_d of a decaying oscillation, from its regular samples.

    Parameters
    ----------
    t : array_like
        Regular time stamps [s].
    v : array_like
        The velocity [unit/s] over the motion.

    Returns
    -------
    complex or None
        s [1/s] with σ < 0 < ω_d, fitted to the triplets of samples of one sign
        (see the module notes); None when fewer than :data:`MIN_TRIPLETS` triplets
        hold, or the fit is not a decaying oscillation.
    """
    t = np.asarray(t, dtype=float)
    v = np.asarray(v, dtype=float)
    if t.size < 3 or t.shape != v.shape:
        return None
    h = float(t[1] - t[0])
    before, now, after = v[:-2], v[1:-1], v[2:]
    sign = np.sign(now)
    one_sign = (sign != 0) & (np.sign(before) == sign) & (np.sign(after) == sign)
    if np.count_nonzero(one_sign) < MIN_TRIPLETS:
        return None
    design = np.column_stack([now[one_sign], before[one_sign]])
    target = after[one_sign]
    keep = np.ones(target.size, dtype=bool)
    for _ in range(_PASSES):
        (p1, p2), *_ = np.linalg.lstsq(design[keep], target[keep], rcond=None)
        # a triplet across a kink the signs do not show (the release from a rest whose
        # noise has the motion's sign) predicts far worse than the others: left out
        misfit = np.abs(target - design @ np.array([p1, p2]))
        keep = misfit <= _OUTLIER * float(np.median(misfit[keep]))
        if np.count_nonzero(keep) < MIN_TRIPLETS:
            return None
    if not (math.isfinite(p1) and math.isfinite(p2) and 0.0 < -p2 < 1.0):
        return None
    decay = 0.5 * math.log(-p2)  # σh
    cosine = p1 / (2.0 * math.exp(decay))
    if not -1.0 < cosine < 1.0:
        return None
    return complex(decay / h, math.acos(cosine) / h)


def _pieces(v: NDArray, s: complex, h: float) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """The damped oscillations the velocity follows step by step.

    Returns the step index, c, and the piece's bounds θ₀ ≤ θ₁ in [0, h] of each piece,
    the velocity there being ``Re(c e^{sθ})`` with θ from the step's first sample: one
    piece a step through its two samples, two at a step where the velocity changes sign
    (through the two samples on each side, meeting at their zero).
    """
    n = v.size - 1
    ahead, back = complex(np.exp(s * h)), complex(np.exp(-s * h))
    # through v[i] and v[i+1]: c = p + iq, Re(c) = v[i], Re(c e^{sh}) = v[i+1]
    c = v[:-1] + 1j * ((v[:-1] * ahead.real - v[1:]) / ahead.imag)
    step = np.arange(n)
    lo, hi = np.zeros(n), np.full(n, h)
    extra_step, extra_c, extra_lo, extra_hi = [], [], [], []
    w = s.imag
    for i in np.flatnonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0):
        if i < 1 or i + 2 >= v.size:
            continue
        # left: through v[i-1], v[i]; right: through v[i+1], v[i+2] (θ' from t[i+1])
        p = v[i]
        left = complex(p, (p * back.real - v[i - 1]) / back.imag)
        pr = v[i + 1]
        right = complex(pr, (pr * ahead.real - v[i + 2]) / ahead.imag)
        # zeros: p cos(wθ) - q sin(wθ) = 0, θ in [0, h] from t[i], in [-h, 0] from t[i+1]
        zero_left = (math.atan2(left.real, left.imag) % math.pi) / w
        zero_right = (math.atan2(right.real, right.imag) % math.pi) / w - math.pi / w
        if not (0.0 <= zero_left <= h and -h <= zero_right <= 0.0):
            continue
        at = 0.5 * (zero_left + h + zero_right)
        c[i], hi[i] = left, at
        extra_step.append(i)
        extra_c.append(right * back)  # θ from t[i]
        extra_lo.append(at)
        extra_hi.append(h)
    return (
        np.concatenate([step, np.asarray(extra_step, dtype=int)]),
        np.concatenate([c, np.asarray(extra_c, dtype=complex)]),
        np.concatenate([lo, np.asarray(extra_lo, dtype=float)]),
        np.concatenate([hi, np.asarray(extra_hi, dtype=float)]),
    )


def integrate_oscillation(t: ArrayLike, v: ArrayLike, s: complex) -> NDArray:
    """∫v dt from the first sample, exact for a damped oscillation of pole ``s`` with
    kinks at its velocity's zeros (see the module notes).

    Parameters
    ----------
    t : array_like
        Regular time stamps [s].
    v : array_like
        The velocity [unit/s].
    s : complex
        The pole [1/s] (:func:`oscillation_pole`).

    Returns
    -------
    ndarray
        The displacement [unit], 0 at the first sample.
    """
    t = np.asarray(t, dtype=float)
    v = np.asarray(v, dtype=float)
    h = float(t[1] - t[0])
    step, c, lo, hi = _pieces(v, s, h)
    moved = (c * (np.exp(s * hi) - np.exp(s * lo)) / s).real
    steps = np.zeros(v.size - 1)
    np.add.at(steps, step, moved)
    out = np.empty(v.size)
    out[0] = 0.0
    np.cumsum(steps, out=out[1:])
    return out


def _square_integral(g: NDArray, s: complex, lo: NDArray, hi: NDArray) -> NDArray:
    """∫ Re(g e^{sθ})² dθ from lo to hi."""
    sigma = s.real
    whole = (g * g * (np.exp(2 * s * hi) - np.exp(2 * s * lo)) / (2 * s)).real
    if sigma == 0.0:
        mean = np.abs(g) ** 2 * (hi - lo)
    else:
        mean = np.abs(g) ** 2 * (np.exp(2 * sigma * hi) - np.exp(2 * sigma * lo)) / (2 * sigma)
    return 0.5 * (whole + mean)


def oscillation_energy(
    t: ArrayLike, v: ArrayLike, x: ArrayLike, s: complex
) -> tuple[NDArray, NDArray]:
    """∫x² dt and ∫v² dt over each step between samples, the velocity followed as
    :func:`integrate_oscillation` integrates it and ``x`` its integral.

    Parameters
    ----------
    t : array_like
        Regular time stamps [s].
    v : array_like
        The velocity [unit/s].
    x : array_like
        The displacement at the samples [unit] (about the equilibrium), whose steps are
        the velocity's integrals (:func:`integrate_oscillation` plus a constant; a slow
        drift of the equilibrium is taken step by step).
    s : complex
        The pole [1/s].

    Returns
    -------
    (ndarray, ndarray)
        ∫x² dt [unit² s] and ∫v² dt [unit² / s] of each of the ``t.size - 1`` steps.
    """
    t = np.asarray(t, dtype=float)
    v = np.asarray(v, dtype=float)
    x = np.asarray(x, dtype=float)
    h = float(t[1] - t[0])
    step, c, lo, hi = _pieces(v, s, h)
    g = c / s
    # x at each piece's start: its step's first sample; a right half (the pieces after
    # the first n) starts where its step's left half, piece ``step``, ends
    n = v.size - 1
    start = x[step].copy()
    right = np.arange(step.size) >= n
    left = step[right]
    start[right] += (c[left] * (np.exp(s * hi[left]) - np.exp(s * lo[left])) / s).real
    centre = start - (g * np.exp(s * lo)).real
    wave = (g * (np.exp(s * hi) - np.exp(s * lo)) / s).real
    x2 = _square_integral(g, s, lo, hi) + 2.0 * centre * wave + centre * centre * (hi - lo)
    v2 = _square_integral(c, s, lo, hi)
    out_x, out_v = np.zeros(n), np.zeros(n)
    np.add.at(out_x, step, x2)
    np.add.at(out_v, step, v2)
    return out_x, out_v
