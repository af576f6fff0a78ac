"""Coulomb friction μ_k N sgn(v), sticking at μ_s (Rigaud et al. 2010, Eq. 5, 7-8).

ΔE(A) = 4μ_k A in the dimensionless form (4 μ_k N A in joules). Without the load
and stiffness μ_k is the friction displacement x_c in the signal's unit.
"""

from __future__ import annotations

from collections.abc import Mapping

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.model.laws.base import Parameter, PhysicalScale, Term, register_term

__all__ = ["COULOMB"]


@numba.njit(cache=True, inline="always")
def _force(a: float, c: NDArray) -> float:
    return c[0]


def _mu_k_prior(amplitude: float) -> dict[str, float | str]:
    # A friction above a quarter of the amplitude stops the motion within two half
    # cycles: such a record has no decay to analyse.
    return {"type": "Uniform", "low": 0.0, "high": amplitude / 4.0}


def _ratio_prior(amplitude: float) -> dict[str, float | str]:
    # Static friction is at least kinetic friction; dry contacts reach several times it
    # (HarmOsc3, a weight sliding on a metal plate: about 5.8, which a bound at 3 held
    # back, moving its friction displacement by 13 posterior sd).
    return {"type": "Uniform", "low": 1.0, "high": 10.0}


def _coefficients(values: Mapping[str, NDArray], reference: float) -> list[NDArray]:
    return [np.asarray(values["mu_k"], dtype=float)]


def _dissipation(amplitude: ArrayLike, values: Mapping[str, NDArray], reference: float) -> NDArray:
    return 4.0 * np.asarray(values["mu_k"], dtype=float) * np.asarray(amplitude, dtype=float)


def _physical(
    values: Mapping[str, NDArray], reference: float, scale: PhysicalScale
) -> dict[str, tuple]:
    mu_k = np.asarray(values["mu_k"], dtype=float)
    if scale.length_unit == "rad":  # a rotation: a friction angle
        return {
            "friction_displacement": (
                mu_k * scale.length_scale,
                "rad",
                "θ_c",
                "friction angle T_c/κ",
            )
        }
    return {
        "friction_displacement": (
            mu_k * scale.length_scale,
            scale.length_unit,
            "x_c",
            "friction displacement μ_k N/k",
        )
    }


COULOMB = register_term(
    Term(
        name="coulomb",
        kind="friction",
        parameters=(
            Parameter(
                "mu_k",
                "μ_k",
                "y",
                0.0,
                float("inf"),
                "kinetic friction coefficient (x_c k/N)",
                _mu_k_prior,
                typical=0.0294,  # glycerol (Rigaud et al. 2010, section 3.1)
            ),
            Parameter(
                "mu_s_ratio",
                "μ_s/μ_k",
                "-",
                1.0,
                float("inf"),
                "static to kinetic friction",
                _ratio_prior,
                typical=1.0,
            ),
        ),
        n_coefficients=1,
        force=_force,
        coefficients=_coefficients,
        dissipation=_dissipation,
        physical=_physical,
        description="Coulomb friction μ_k N sgn v, sticking at μ_s, ΔE = 4μ_kNA",
        amount="mu_k",
        absent="no friction (x_c or μ_k = 0)",
        sticks=True,
    )
)
