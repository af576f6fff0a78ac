"""Numerically stable elementary functions used by the closed forms.

Each function has a removable singularity that the plain formula turns into 0/0
or into catastrophic cancellation; the limits are the ones the physics needs
(ζ → 0 is pure Coulomb friction, μ_k → 0 pure viscous damping).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["TINY", "expm1_ratio", "geometric_sum", "gminus", "log1p_ratio"]

_SERIES_CUTOFF = 1e-3
# Arguments below this are treated as 0: the limit is then exact to double precision,
# while subnormal arguments would lose their significant digits.
TINY = 1e-100


def expm1_ratio(a: NDArray, length: NDArray) -> NDArray:
    """(1 - exp(-a L))/a, the integral of exp(-a s) over [0, L]; equals L at a = 0."""
    a = np.asarray(a, dtype=float)
    length = np.asarray(length, dtype=float)
    tiny = np.abs(a) < TINY
    safe = np.where(tiny, 1.0, a)
    return np.where(tiny, length, -np.expm1(-safe * length) / safe)


def log1p_ratio(w: NDArray) -> NDArray:
    """-log(1 - w)/w for 0 <= w <= 1; equals 1 at w = 0 and +inf at w = 1."""
    w = np.asarray(w, dtype=float)
    tiny = w < TINY
    safe = np.where(tiny, 0.5, w)
    with np.errstate(divide="ignore"):
        return np.where(tiny, 1.0, -np.log1p(-safe) / safe)


def gminus(z: NDArray) -> NDArray:
    """exp(-z) - 1 + z, accurate for small z (a Taylor series below 1e-3)."""
    z = np.asarray(z, dtype=float)
    series = z * z * (0.5 - z * (1.0 / 6.0 - z * (1.0 / 24.0 - z * (1.0 / 120.0 - z / 720.0))))
    return np.where(z < _SERIES_CUTOFF, series, np.expm1(-z) + z)


def geometric_sum(length: NDArray, x: NDArray) -> NDArray:
    """Σ_{i<L} exp(-i x) = (1 - e^{-Lx})/(1 - e^{-x}); equals L at x = 0."""
    length = np.asarray(length, dtype=float)
    x = np.asarray(x, dtype=float)
    tiny = x < TINY
    safe = np.where(tiny, 1.0, x)
    return np.where(tiny, length, np.expm1(-safe * length) / np.expm1(-safe))
