"""Viscous-only decrements: logarithmic decrement and exponential envelope (ζ₀).

For a test without contact (μ_k = 0) the turning points decay geometrically:
|Y_{n+1}| = r |Y_n| with r = exp(-βπ) per half-cycle (Eq. 20 with μ_k = 0) and
β = ζ/√(1-ζ²) (Eq. 14). Both estimators assume μ_k = 0; on a record with friction
they attribute the friction to ζ and overestimate it (the linear part of the decay
looks like extra viscous damping).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.optimize

from bayestribo.errors import RecordingError
from bayestribo.estimators._common import check_peaks, describe, make_estimate, omega
from bayestribo.estimators.result import Estimate
from bayestribo.model.scaling import Rig
from bayestribo.signal.peaks import Peaks

__all__ = ["exponential_envelope", "log_decrement"]

_VISCOUS_NOTE = "assumes no friction (μ_k = 0); with friction ζ is overestimated"


def log_decrement(peaks: Peaks, rig: Rig | None = None) -> Estimate:
    """Logarithmic decrement of the first and last peaks (Rayleigh), viscous only.

    β = ln(|Y_0|/|Y_n|)/(nπ) over n half-cycles (Eq. 20 with μ_k = 0), ζ from Eq. 14.
    For velocity peaks the same ratio holds (the velocity extremum is a fixed
    fraction of the displacement amplitude in every half-cycle, Eq. 17).

    Parameters
    ----------
    peaks : Peaks
        Successive turning points about the equilibrium (at least 2).
    rig : Rig, optional
        Only used for Ω in the details.

    Returns
    -------
    Estimate
        ``zeta`` with a standard error propagated from the noise of one peak value
        (``peaks.value_noise``): se(β) = σ √(1/Y_0² + 1/Y_n²)/(nπ).
    """
    check_peaks(peaks, 2, "log_decrement")
    a = np.abs(peaks.value)
    if a[0] == 0 or a[-1] == 0:
        raise RecordingError("log_decrement: a peak value is zero about the equilibrium")
    n = a.size - 1
    beta = math.log(a[0] / a[-1]) / (n * math.pi)
    se = peaks.value_noise * math.sqrt(1.0 / a[0] ** 2 + 1.0 / a[-1] ** 2) / (n * math.pi)
    return make_estimate(
        "log_decrement",
        peaks,
        rig,
        beta=beta,
        beta_se=se,
        omega_=omega(peaks, rig, beta / math.sqrt(1 + beta * beta)),
        data=describe(peaks, f"first and last of {n} half-cycles"),
        notes=_VISCOUS_NOTE + "; SE from the peak noise only",
    )


def exponential_envelope(peaks: Peaks, rig: Rig | None = None) -> Estimate:
    """Least-squares exponential envelope |Y_n| = A exp(-λ (t_n - t_0)), viscous only.

    λ = ζΩ and the half-period is T = π/(Ω√(1-ζ²)) (Eq. 13), so β = λT/π and ζ from
    Eq. 14. The fit is on the amplitudes (not their logarithm) so that additive noise
    keeps equal weights; T is the least-squares slope of the peak times.

    Parameters
    ----------
    peaks : Peaks
        Successive turning points about the equilibrium (at least 3).
    rig : Rig, optional
        Only used for Ω in the details.

    Returns
    -------
    Estimate
        ``zeta`` and its standard error from the Jacobian of the fit (residual
        variance estimated from the fit; correlations between peaks ignored).
    """
    check_peaks(peaks, 3, "exponential_envelope")
    a = np.abs(peaks.value)
    t = peaks.t - peaks.t[0]
    half = peaks.half_period
    lam0 = max(math.log(a[0] / a[-1]) / max(t[-1], 1e-300), 0.0) if a[-1] > 0 else 0.0

    def resid(p: np.ndarray) -> np.ndarray:
        return p[0] * np.exp(-p[1] * t) - a

    sol = scipy.optimize.least_squares(
        resid, [a[0], lam0], x_scale=[a[0], 1.0 / max(t[-1], 1e-300)], method="lm"
    )
    amp, lam = sol.x
    dof = a.size - 2
    se_lam = None
    if dof > 0:
        s2 = float(np.sum(sol.fun**2)) / dof
        try:
            cov = np.linalg.inv(sol.jac.T @ sol.jac) * s2
            se_lam = math.sqrt(max(cov[1, 1], 0.0))
        except np.linalg.LinAlgError:
            se_lam = None
    beta = lam * half / math.pi
    return make_estimate(
        "exponential_envelope",
        peaks,
        rig,
        beta=beta,
        beta_se=None if se_lam is None else se_lam * half / math.pi,
        omega_=omega(peaks, rig, beta / math.sqrt(1 + beta * beta)),
        data=describe(peaks),
        notes=_VISCOUS_NOTE,
        details={"amplitude": float(amp), "lambda_per_s": float(lam)},
    )
