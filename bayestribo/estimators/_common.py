"""Helpers shared by the peak-based estimators (not public)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import RecordingError
from bayestribo.estimators.result import Estimate, friction_fraction
from bayestribo.model.scaling import Rig
from bayestribo.signal.peaks import Peaks

__all__: list[str] = []


def zeta_from_beta(beta: float) -> float:
    """ζ from β = ζ/√(1-ζ²) (Eq. 14 inverted): ζ = β/√(1+β²)."""
    return beta / math.sqrt(1.0 + beta * beta)


def dzeta_dbeta(beta: float) -> float:
    """Derivative of ζ(β) = β/√(1+β²): (1+β²)^(-3/2)."""
    return (1.0 + beta * beta) ** -1.5


def check_peaks(peaks: Peaks, needed: int, method: str) -> None:
    if not isinstance(peaks, Peaks):
        raise RecordingError(
            f"{method}: peaks must be a bayestribo.signal.peaks.Peaks, got {type(peaks)}"
        )
    if len(peaks) < needed:
        raise RecordingError(f"{method}: needs at least {needed} peaks, got {len(peaks)}")


def alternating_sign(peaks: Peaks) -> NDArray:
    """s_n = s_0 (-1)^n: the sign pattern of successive turning points (Eq. 19)."""
    z = peaks.amplitudes()
    s0 = 1.0 if z[0] >= 0 else -1.0
    return s0 * (-1.0) ** np.arange(z.size)


def omega(peaks: Peaks, rig: Rig | None, zeta: float) -> float:
    """Ω [rad/s]: from the rig, or from the damped half-period π/(Ω√(1-ζ²)) (Eq. 13)."""
    if rig is not None:
        return rig.omega
    z = min(abs(zeta), 0.999)
    return math.pi / (peaks.half_period * math.sqrt(1.0 - z * z))


def velocity_peak_factor(beta: float) -> float:
    """K with Y'_n = -K (Y_n - μ_k sgn Y_n): velocity extremum of a half-cycle (Eq. 17).

    y' ∝ e^{-ζs} sin(ωs) is extreme where tan(ωs*) = ω/ζ, hence sin(ωs*) = ω and
    K = e^{-ζ s*} = exp(-β atan(1/β)) (K = 1 at β = 0).
    """
    if beta == 0.0:
        return 1.0
    return math.exp(-beta * math.atan2(1.0, beta))


def length_amplitudes(peaks: Peaks, beta: float, omega_: float) -> NDArray:
    """Peaks as lengths: Y_n (displacement) or -Y'_n/(KΩ) = Y_n - x_c sgn(Y_n) (velocity)."""
    z = peaks.amplitudes()
    if peaks.kind == "velocity":
        return z / (velocity_peak_factor(beta) * omega_)
    return z


def friction_factor(kind: str, r: float) -> float:
    """b/x_c in Z_{n+1} = -r Z_n + b s_n: 1 + r for displacement peaks (Eq. 20), 2 for
    velocity peaks (amplitude about the arc centre, A_{n+1} = -r A_n + 2 x_c s_n)."""
    return 1.0 + r if kind == "displacement" else 2.0


def describe(peaks: Peaks, extra: str = "") -> str:
    name = "displacement" if peaks.kind == "displacement" else "velocity"
    text = f"{name} peaks (n={len(peaks)})"
    return f"{text}, {extra}" if extra else text


def make_estimate(
    method: str,
    peaks: Peaks,
    rig: Rig | None,
    *,
    beta: float | None,
    beta_se: float | None,
    xc: float | None = None,
    xc_se: float | None = None,
    omega_: float | None = None,
    data: str = "",
    notes: str = "",
    details: Mapping[str, Any] | None = None,
) -> Estimate:
    """Assemble an Estimate: ζ from β (Eq. 14), μ_k = x_c k/N when the rig allows."""
    zeta = None if beta is None else zeta_from_beta(beta)
    zeta_se = None if beta_se is None or beta is None else beta_se * dzeta_dbeta(beta)
    mu = mu_se = None
    scaling = rig.scaling() if rig is not None else None
    if xc is not None and scaling is not None and scaling.friction_defined:
        mu = float(scaling.mu_k(xc))
        mu_se = None if xc_se is None else float(scaling.mu_k(xc_se))
    share = None
    if zeta is not None and xc is not None and len(peaks) >= 1 and omega_ is not None:
        amps = np.abs(length_amplitudes(peaks, beta, omega_))
        if peaks.kind == "velocity":
            amps = amps + xc  # amplitude about the equilibrium, not the arc centre
        a0 = float(amps[0])
        a_end = 0.0 if peaks.stop_time is not None else float(amps[-1])
        if a0 > a_end:
            share = friction_fraction(zeta, xc, a0, a_end)
    d = {"beta": beta, "beta_se": beta_se}
    if omega_ is not None:
        d["omega"] = omega_
    d.update(details or {})
    return Estimate(
        method=method,
        zeta=zeta,
        zeta_se=zeta_se,
        mu_k=mu,
        mu_k_se=mu_se,
        friction_displacement=xc,
        friction_displacement_se=xc_se,
        data=data or describe(peaks),
        notes=notes,
        friction_fraction=share,
        details=d,
    )
