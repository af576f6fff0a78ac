"""Cubic drag c₃ v³: a drag that grows faster than the square of the speed.

Dimensionless: a force ``c₃ y'³`` (c₃ in units of 1/y²), so
``ΔE(A) = (3π/4) c₃ A⁴`` (from ∮|sin τ|⁴ dτ = 3π/4). With ``coulomb``, ``viscous`` and
``quadratic`` it completes a dissipation per cycle that is any polynomial of degree 1
to 4 in the amplitude with non-negative coefficients, a smooth increasing function:
the law-free fit of :mod:`bayestribo.inference.comparison` (``law="free"``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.model.laws.base import Parameter, PhysicalScale, Term, register_term

__all__ = ["CUBIC"]


@numba.njit(cache=True, inline="always")
def _force(w: float, c: NDArray) -> float:
    return c[0] * w * w * w


def _prior(amplitude: float) -> dict[str, float | str]:
    # Up to the dissipation of ζ = 0.3 at the initial amplitude, (3π/4)c₃A⁴ = 0.6πA².
    return {"type": "Uniform", "low": 0.0, "high": 0.8 / amplitude**2}


def _coefficients(values: Mapping[str, NDArray], reference: float) -> list[NDArray]:
    return [np.asarray(values["c3"], dtype=float)]


def _dissipation(amplitude: ArrayLike, values: Mapping[str, NDArray], reference: float) -> NDArray:
    a = np.asarray(amplitude, dtype=float)
    return 0.75 * math.pi * np.asarray(values["c3"], dtype=float) * a**4


def _physical(
    values: Mapping[str, NDArray], reference: float, scale: PhysicalScale
) -> dict[str, tuple]:
    c3 = np.asarray(values["c3"], dtype=float)
    # m ẍ + c₃ẋ³ + kx = 0 with x = ℓy, t = τ/Ω: the dimensionless c₃ is c₃ℓ²Ω/m
    per_mass = c3 / (scale.length_scale**2 * scale.omega)
    if scale.mass is not None:
        return {"c3_SI": (per_mass * scale.mass, "kg s/m²", "c₃", "cubic drag coefficient")}
    return {
        "c3_per_mass": (
            per_mass,
            f"s/{scale.length_unit}^2",
            "c₃/m",
            "cubic drag coefficient per unit mass",
        )
    }


CUBIC = register_term(
    Term(
        name="cubic",
        kind="drag",
        parameters=(
            Parameter("c3", "c₃", "1/y²", 0.0, float("inf"), "cubic drag (dimensionless)", _prior),
        ),
        n_coefficients=1,
        force=_force,
        coefficients=_coefficients,
        dissipation=_dissipation,
        physical=_physical,
        description="cubic drag c₃ v³, ΔE = (3π/4)c₃Ω³A⁴",
        amount="c3",
        absent="no cubic drag (c₃ = 0)",
        # the law-free fit's fourth power, not a mechanism law="auto" compares
        compared=False,
    )
)
