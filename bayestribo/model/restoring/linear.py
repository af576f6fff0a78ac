"""The linear spring: V(y) = y²/2, a half period that does not depend on the swing."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.model.restoring.base import (
    RestoringForce,
    builtin_description,
    register_builtin,
)

__all__ = ["LINEAR"]


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
