r"""Friction that varies with amplitude: η |Y_n| sgn v within each half cycle.

With :mod:`coulomb` it makes a friction that varies with amplitude,
``μ(A) = μ_k + ηA`` (A the turning point the half cycle started from, in units of ℓ):
η > 0 grows with amplitude, η < 0 falls with it (as a velocity-weakening contact's
does: a larger swing is a faster one). HarmOsc3, a weight sliding on a metal plate,
has η = -0.0027 ± 0.00003 (μ(A) 16 % lower at its largest swing), which cut its χ²
from 8332 to 1275. Alone (η > 0) it is the classical hysteretic (structural) damping,
whose loss per cycle grows as the square of the amplitude like a viscous one but does
not depend on frequency. ΔE(A) = 4ηA² (loss factor 4η/π). A friction below zero at
some amplitude of the motion is outside the law's domain (no likelihood there).
"""

from __future__ import annotations

from collections.abc import Mapping

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.model.laws.base import Parameter, PhysicalScale, Term, register_term

__all__ = ["HYSTERETIC"]


@numba.njit(cache=True, inline="always")
def _force(a: float, c: NDArray) -> float:
    return c[0] * a


def _prior(amplitude: float) -> dict[str, float | str]:
    # Up to about the dissipation of ζ = 0.3 (4η = 0.6π), either way: with coulomb, a
    # friction that grows or falls with amplitude (the motion keeps μ(A) >= 0).
    return {"type": "Uniform", "low": -0.45, "high": 0.45}


def _coefficients(values: Mapping[str, NDArray], reference: float) -> list[NDArray]:
    return [np.asarray(values["eta"], dtype=float)]


def _dissipation(amplitude: ArrayLike, values: Mapping[str, NDArray], reference: float) -> NDArray:
    a = np.asarray(amplitude, dtype=float)
    return 4.0 * np.asarray(values["eta"], dtype=float) * a * a


def _physical(
    values: Mapping[str, NDArray], reference: float, scale: PhysicalScale
) -> dict[str, tuple]:
    eta = np.asarray(values["eta"], dtype=float)
    return {"loss_factor": (4.0 * eta / np.pi, "-", "η_loss", "hysteretic loss factor 4η/π")}


HYSTERETIC = register_term(
    Term(
        name="hysteretic",
        kind="friction",
        parameters=(
            Parameter(
                "eta",
                "η",
                "-",
                -1.0,
                1.0,
                "friction per unit amplitude (μ(A) = μ_k + ηA)",
                _prior,
                null=0.0,
            ),
        ),
        n_coefficients=1,
        force=_force,
        coefficients=_coefficients,
        dissipation=_dissipation,
        physical=_physical,
        description="friction proportional to amplitude η|Y| sgn v (with coulomb: μ_k + ηA)",
        # its ΔE(A) = 4ηA² has viscous damping's shape (2πζA²): η and ζ trade along a
        # ridge, which one increment per half cycle hardly resolves
        overlaps=("viscous",),
    )
)
