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

__all__ = ["MIN_TRIPLETS", "integrate_oscillation", "oscillation_pole", "step_rule"]

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
    a, b = step_rule(s, h)
    steps = a * v[:-1] + b * v[1:]
    back, ahead = complex(np.exp(-s * h)), complex(np.exp(s * h))
    w = s.imag
    for i in np.flatnonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0):
        if i < 1 or i + 2 >= v.size:
            continue
        # the damped oscillation through v[i-1], v[i] (left) and v[i+1], v[i+2] (right),
        # c = p + iq with Re(c) = v[i] and Re(c e^{-sh}) = v[i-1]
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
        piece_left = left * (np.exp(s * at) - 1.0) / s
        piece_right = right * (1.0 - np.exp(s * (at - h))) / s
        steps[i] = piece_left.real + piece_right.real
    out = np.empty(v.size)
    out[0] = 0.0
    np.cumsum(steps, out=out[1:])
    return out
