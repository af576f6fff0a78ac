"""The linear spring: V(y) = y²/2, a half period that does not depend on the swing."""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.model.restoring.base import (
    RestoringForce,
    builtin_description,
    register_builtin,
)

__all__ = ["LINEAR", "potential_kernel", "spring_kernel"]


@numba.njit(cache=True, inline="always")
def spring_kernel(y: float, k: NDArray) -> float:
    """V'(y) = y: the linear spring as the nonlinear integrator takes it (its tests hold
    it to the closed form; a fit on a linear spring takes the closed form or the
    polar integrator instead)."""
    return y


@numba.njit(cache=True, inline="always")
def potential_kernel(y: float, k: NDArray) -> float:
    """V(y) = y²/2."""
    return 0.5 * y * y


def _potential(y: ArrayLike) -> NDArray:
    y = np.asarray(y, dtype=float)
    return 0.5 * y * y


def _ratio(a: ArrayLike) -> NDArray:
    return np.ones_like(np.asarray(a, dtype=float))


LINEAR = register_builtin(
    RestoringForce(
        name="linear",
        description=builtin_description("linear"),
        potential=_potential,
        half_period_ratio=_ratio,
    )
)
