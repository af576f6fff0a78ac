"""The pendulum: θ'' + sin θ = 0 (τ = ω₀t), V(θ) = 1 - cos θ, θ in radians.

The half period of the undamped swing A is ``T(A)/T₀ = 2K(m)/π`` with
``m = sin²(A/2)`` and K the complete elliptic integral of the first kind
(:func:`scipy.special.ellipk`, whose argument is m): 1.180 at 90°, 1.373 at 120°.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.model.restoring.base import (
    RestoringForce,
    builtin_description,
    register_builtin,
)

__all__ = ["PENDULUM"]


def _potential(theta: ArrayLike) -> NDArray:
    theta = np.asarray(theta, dtype=float)
    # 1 - cos θ = 2 sin²(θ/2): no cancellation at small angles
    return 2.0 * np.sin(0.5 * theta) ** 2


def _spring(theta: ArrayLike) -> NDArray:
    return np.sin(np.asarray(theta, dtype=float))


@numba.njit(cache=True, inline="always")
def spring_kernel(y: float, k: NDArray) -> float:
    """V'(θ) = sin θ."""
    return math.sin(y)


@numba.njit(cache=True, inline="always")
def potential_kernel(y: float, k: NDArray) -> float:
    """V(θ) = 1 - cos θ = 2 sin²(θ/2)."""
    s = math.sin(0.5 * y)
    return 2.0 * s * s


def _ratio(a: ArrayLike) -> NDArray:
    import scipy.special

    a = np.abs(np.asarray(a, dtype=float))
    if np.any(a >= np.pi):
        raise ValueError("a pendulum's swing must be below π (it would turn over)")
    return 2.0 * scipy.special.ellipk(np.sin(0.5 * a) ** 2) / np.pi


PENDULUM = register_builtin(
    RestoringForce(
        name="pendulum",
        description=builtin_description("pendulum"),
        potential=_potential,
        half_period_ratio=_ratio,
        angle=True,
        spring=_spring,
        kernels=(spring_kernel, potential_kernel),
    )
)
