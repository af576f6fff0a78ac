r"""Power-law drag c_α |v|^α sgn v, the exponent α free.

Sampled as the equivalent damping ratio ζ_α at the reference amplitude A_r (the
observed initial amplitude) and α: the dimensionless force is ``c |y'|^α`` with
``c = 2πζ_α A_r^{1-α}/K(α+1)``, ``K(p) = ∮|sin τ|^p dτ = 2√π Γ((p+1)/2)/Γ(p/2+1)``,
so that ``ΔE(A) = c K(α+1) A^{α+1} = 2πζ_α A_r² (A/A_r)^{α+1}`` (at α = 1 this is
viscous damping with ζ = ζ_α). Sampling ζ_α instead of c keeps the two parameters
nearly independent: c alone would trade off against α over the decay's amplitudes.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.model.laws.base import (
    Parameter,
    PhysicalScale,
    Term,
    harmonic_power_integral,
    register_term,
)

__all__ = ["POWER"]


@numba.njit(cache=True, inline="always")
def _force(w: float, c: NDArray) -> float:
    if w <= 0.0:
        return 0.0
    return c[0] * w ** c[1]


def _zeta_prior(amplitude: float) -> dict[str, float | str]:
    return {"type": "Uniform", "low": 0.0, "high": 0.3}


def _alpha_prior(amplitude: float) -> dict[str, float | str]:
    return {"type": "Uniform", "low": 0.0, "high": 3.0}


def _coefficients(values: Mapping[str, NDArray], reference: float) -> list[NDArray]:
    zeta = np.asarray(values["zeta_alpha"], dtype=float)
    alpha = np.asarray(values["alpha"], dtype=float)
    c = 2.0 * math.pi * zeta * reference ** (1.0 - alpha) / harmonic_power_integral(alpha + 1.0)
    return [c, alpha]


def _dissipation(amplitude: ArrayLike, values: Mapping[str, NDArray], reference: float) -> NDArray:
    zeta = np.asarray(values["zeta_alpha"], dtype=float)
    alpha = np.asarray(values["alpha"], dtype=float)
    a = np.asarray(amplitude, dtype=float)
    return 2.0 * math.pi * zeta * reference**2 * (a / reference) ** (alpha + 1.0)


def _physical(
    values: Mapping[str, NDArray], reference: float, scale: PhysicalScale
) -> dict[str, tuple]:
    c, alpha = _coefficients(values, reference)
    # m ẍ + c_α|ẋ|^α + kx = 0 with x = ℓy, t = τ/Ω: c = c_α (ℓΩ)^α/(kℓ).
    per_k = c * scale.length_scale ** (1.0 - alpha) * scale.omega ** (-alpha)
    if scale.stiffness is not None:
        return {"c_alpha_SI": (per_k * scale.stiffness, "N (s/m)^α", "c_α", "power-law drag")}
    return {
        "c_alpha_per_k": (
            per_k,
            f"{scale.length_unit}^(1-α) s^α",
            "c_α/k",
            "power-law drag per unit stiffness",
        )
    }


POWER = register_term(
    Term(
        name="power",
        kind="drag",
        parameters=(
            Parameter(
                "zeta_alpha",
                "ζ_α",
                "-",
                0.0,
                1.0,
                "equivalent damping ratio of the power-law drag at the initial amplitude",
                _zeta_prior,
            ),
            Parameter("alpha", "α", "-", 0.0, 5.0, "exponent of the power-law drag", _alpha_prior),
        ),
        n_coefficients=2,
        force=_force,
        coefficients=_coefficients,
        dissipation=_dissipation,
        physical=_physical,
        description="power-law drag c_α |v|^α sgn v, α free, ΔE ∝ A^(α+1)",
        amount="zeta_alpha",
        absent="no power-law drag (ζ_α = 0; α then free)",
        smooth=False,
        # α = 1 is viscous damping (ΔE ∝ A², as a friction proportional to amplitude
        # makes it) and α = 2 quadratic drag, both inside α's prior: with either, ζ_α
        # trades against the other term along a ridge. α = 0 (a friction without
        # sticking) is the prior's bound, and with Coulomb friction the law describes
        # drag of any power beside a friction that sticks
        overlaps=("viscous", "quadratic", "hysteretic"),
    )
)
