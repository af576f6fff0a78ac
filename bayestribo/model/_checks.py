"""Argument checks shared by the forward models."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["all_within", "as_finite", "check_parameters"]


def all_within(value: NDArray, low: float, high: float = np.inf) -> bool:
    """Every element of the float array ``value`` finite and in [low, high), ``low``
    finite.

    Two reductions (a NaN fails both comparisons, ±inf one of them): the quick test of
    arguments that are usually right, before the checks that name what is wrong.
    """
    if value.size == 0:
        return True
    return bool(value.min() >= low) and bool(value.max() < high)


def as_finite(name: str, value: ArrayLike) -> NDArray:
    """Return ``value`` as a float array; raise ``ValueError`` naming it if not finite."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric, got {value!r}") from exc
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got non-finite values in {name}")
    return arr


def check_parameters(
    zeta: ArrayLike, mu_k: ArrayLike, mu_s: ArrayLike | None = None
) -> tuple[NDArray, NDArray, NDArray | None]:
    """Check 0 <= ζ < 1, μ_k >= 0 and μ_s >= μ_k; return them as float arrays.

    Raises
    ------
    ValueError
        Naming the argument and the range that was expected.
    """
    z = as_finite("zeta", zeta)
    if np.any(z < 0.0) or np.any(z >= 1.0):
        raise ValueError(f"zeta must satisfy 0 <= zeta < 1 (underdamped), got {zeta!r}")
    mk = as_finite("mu_k", mu_k)
    if np.any(mk < 0.0):
        raise ValueError(f"mu_k must be >= 0, got {mu_k!r}")
    if mu_s is None:
        return z, mk, None
    ms = as_finite("mu_s", mu_s)
    if np.any(ms < mk):
        raise ValueError(f"mu_s must be >= mu_k (static friction at least kinetic), got {mu_s!r}")
    return z, mk, ms
