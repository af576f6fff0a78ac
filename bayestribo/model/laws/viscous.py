"""Viscous damping: a force 2ζ y' (Rigaud et al. 2010, Eq. 7), ΔE(A) = 2πζA²."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.model.laws.base import Parameter, PhysicalScale, Term, register_term

__all__ = ["VISCOUS"]


@numba.njit(cache=True, inline="always")
def _force(w: float, c: NDArray) -> float:
    return c[0] * w


def _prior(amplitude: float) -> dict[str, float | str]:
    return {"type": "Uniform", "low": 0.0, "high": 0.3}


def _coefficients(values: Mapping[str, NDArray], reference: float) -> list[NDArray]:
    return [2.0 * np.asarray(values["zeta"], dtype=float)]


def _dissipation(amplitude: ArrayLike, values: Mapping[str, NDArray], reference: float) -> NDArray:
    a = np.asarray(amplitude, dtype=float)
    return 2.0 * math.pi * np.asarray(values["zeta"], dtype=float) * a * a


def _physical(
    values: Mapping[str, NDArray], reference: float, scale: PhysicalScale
) -> dict[str, tuple]:
    zeta = np.asarray(values["zeta"], dtype=float)
    out = {}
    if scale.mass is not None:
        out["c"] = (
            2.0 * zeta * scale.mass * scale.omega,
            "N s/m",
            "c",
            "viscous damping coefficient 2ζmΩ",
        )
    return out


VISCOUS = register_term(
    Term(
        name="viscous",
        kind="drag",
        parameters=(
            Parameter(
                "zeta",
                "ζ",
                "-",
                0.0,
                1.0,
                "equivalent viscous damping ratio",
                _prior,
                typical=0.0236,  # glycerol (Rigaud et al. 2010, section 3.1)
            ),
        ),
        n_coefficients=1,
        force=_force,
        coefficients=_coefficients,
        dissipation=_dissipation,
        physical=_physical,
        description="viscous damping c v (ζ = c/(2mΩ)), ΔE = 2πζkA²",
        amount="zeta",
        absent="no viscous damping (ζ = 0)",
    )
)
