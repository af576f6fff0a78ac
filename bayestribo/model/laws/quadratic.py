"""Quadratic drag c₂ v|v| (air or fluid drag at high Reynolds number).

Dimensionless: a force γ y'|y'| with γ = c₂ℓ/m (ℓ the length scale), so
ΔE(A) = (8/3)γA³ (from ∮|sin τ|³ dτ = 8/3), or (8/3) c₂ Ω² A³ in joules.
"""

from __future__ import annotations

from collections.abc import Mapping

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.model.laws.base import Parameter, PhysicalScale, Term, register_term

__all__ = ["QUADRATIC"]


@numba.njit(cache=True, inline="always")
def _force(w: float, c: NDArray) -> float:
    return c[0] * w * w


def _prior(amplitude: float) -> dict[str, float | str]:
    # Up to the dissipation of ζ = 0.3 at the initial amplitude, (8/3)γA³ = 0.6πA².
    return {"type": "Uniform", "low": 0.0, "high": 0.225 * 3.141592653589793 / amplitude}


def _coefficients(values: Mapping[str, NDArray], reference: float) -> list[NDArray]:
    return [np.asarray(values["c2"], dtype=float)]


def _dissipation(amplitude: ArrayLike, values: Mapping[str, NDArray], reference: float) -> NDArray:
    a = np.asarray(amplitude, dtype=float)
    return (8.0 / 3.0) * np.asarray(values["c2"], dtype=float) * a**3


def _physical(
    values: Mapping[str, NDArray], reference: float, scale: PhysicalScale
) -> dict[str, tuple]:
    gamma = np.asarray(values["c2"], dtype=float)
    per_mass = gamma / scale.length_scale
    if scale.mass is not None:
        return {"c2_SI": (per_mass * scale.mass, "kg/m", "c₂", "quadratic drag coefficient")}
    return {
        "c2_per_mass": (
            per_mass,
            f"1/{scale.length_unit}",
            "c₂/m",
            "quadratic drag coefficient per unit mass",
        )
    }


QUADRATIC = register_term(
    Term(
        name="quadratic",
        kind="drag",
        parameters=(
            Parameter("c2", "γ", "1/y", 0.0, float("inf"), "quadratic drag (c₂ℓ/m)", _prior),
        ),
        n_coefficients=1,
        force=_force,
        coefficients=_coefficients,
        dissipation=_dissipation,
        physical=_physical,
        description="quadratic drag c₂ v|v| (air, fluid), ΔE = (8/3)c₂Ω²A³",
        amount="c2",
        absent="no quadratic drag (c₂ = 0)",
    )
)
