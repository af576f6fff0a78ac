"""The paper's method: least squares on the retrograde energy integral Π (Eq. 39-42).

From a recording (displacement and/or velocity), the energy E = (y² + y'²)/2 (Eq. 26)
is integrated backwards from the end of the motion, Π(τ) = ∫_τ^{T} E dθ (Eq. 39),
and ζ, μ_k and the initial amplitude Y_0 are fitted by least squares,
minimising Δ_Π = √(mean (Π_exp - Π_num)²) (Eq. 42), with either

* ``model="averaged"``: Π_app of Eq. 40 with the corrected constant of Eq. 41,
  A = (Γ²/ζ)(3/4 - ½ ln(Γ/Λ)) (the scan shows 3/4 - ln(Γ/Λ); integrating Eq. 35 from
  τ to T_f of Eq. 38 gives the ½), via :func:`bayestribo.model.averaged_pi`; or
* ``model="exact"``: the exact piecewise response (Eq. 16-17) integrated in closed
  form, :func:`bayestribo.model.exact_pi`, with μ_s = μ_k unless given (the pin
  sticks at the first turning point where it cannot restart).

The recording becomes E(τ) in :func:`bayestribo.signal.decay.energy_decay`, the
one path the Bayesian fit uses too (:func:`energy_data`). Both Π are integrated to
the same end T (the detected end of motion, or the last sample of a record that ends
while still moving; the model is truncated there), so the record length does not
bias the fit. The analysis starts at the sample nearest a turning point (y' ≈ 0,
the initial state of Eq. 15) after ``skip_oscillations`` oscillations counted from
the release, as in the Bayesian fit; the exact model starts from
that sample's velocity.

The covariance is the usual Gauss-Newton one, s²(JᵀJ)⁻¹ with s² = RSS/(n - 3). The
residuals of Π are strongly correlated (Π is a running integral), so these standard
errors are much too small as uncertainties; they are given because the classical
method gives them, and the Bayesian fit exists to do better.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
import scipy.optimize
from numpy.typing import ArrayLike, NDArray

from bayestribo.errors import RecordingError
from bayestribo.estimators.feeny_liang import feeny_liang
from bayestribo.estimators.result import Estimate, friction_fraction
from bayestribo.model.scaling import Rig
from bayestribo.signal.decay import energy_decay, retrograde_integral
from bayestribo.signal.increments import sample_noise_bias
from bayestribo.signal.peaks import Peaks

__all__ = ["MIN_TURNING_POINTS", "EnergyData", "energy_data", "energy_least_squares"]

Model = Literal["averaged", "exact"]


@dataclass(frozen=True)
class EnergyData:
    """Dimensionless energy decay of a recording, ready for the Π least squares.

    Attributes
    ----------
    tau : ndarray
        τ = Ω(t - t_start) of the analysed samples [-].
    y, yp : ndarray
        Dimensionless displacement and velocity about the equilibrium (Eq. 6).
    energy : ndarray
        E = (y² + y'²)/2 minus the mean noise energy per sample (Eq. 26,
        :func:`bayestribo.signal.increments.sample_noise_bias`).
    pi : ndarray
        Π(τ) = ∫_τ^{τ_end} E dθ by the trapezoidal rule (Eq. 39).
    tau_end : float
        End of the integration (end of motion, or last sample).
    omega : float
        Ω used [rad/s].
    length_scale : float
        ℓ [signal length unit] (N/k with a loaded rig, else 1).
    peaks : Peaks
        Displacement turning points used for the start, end and offset.
    stopped : bool
        True when the record shows the motion stopping (rest tail).
    source : str
        Which signals were measured and which derived.
    start_time : float
        Time of the first analysed sample [s] (a turning point after the skipped
        oscillations).
    """

    tau: NDArray
    y: NDArray
    yp: NDArray
    energy: NDArray
    pi: NDArray
    tau_end: float
    omega: float
    length_scale: float
    peaks: Peaks
    stopped: bool
    source: str
    start_time: float = float("nan")


#: Fewest turning points the Π least squares needs after the skipped ones.
MIN_TURNING_POINTS = 3

_SOURCES = {
    None: "x measured, v measured",
    "velocity": "x measured, v derived from x",
    "displacement": "x integrated from v, v measured",
}


def energy_data(
    t: ArrayLike,
    x: ArrayLike | None = None,
    v: ArrayLike | None = None,
    *,
    rig: Rig | None = None,
    skip_oscillations: int = 1,
    offset: float | Literal["auto", "constant"] | None = "auto",
) -> EnergyData:
    """Prepare E(τ) and Π(τ) of a recording for the Π least squares (Eq. 26, 39).

    The recording becomes an energy decay in :func:`bayestribo.signal.decay.energy_decay`,
    as for the Bayesian fit (time check, release, equilibrium, end of motion, derived
    channel); here the mean noise energy of each sample
    (:func:`bayestribo.signal.increments.sample_noise_bias`) is removed from E before
    Π is integrated.

    Parameters
    ----------
    t : array_like
        Sample times [s], strictly increasing and regular.
    x : array_like, optional
        Displacement [m with a loaded rig, else any length unit].
    v : array_like, optional
        Velocity [same length unit/s]. At least one of ``x`` and ``v``; a missing
        one is derived (Savitzky-Golay derivative of x, or trapezoidal integral of v).
    rig : Rig, optional
        Ω (the rig's nominal natural frequency) and, with mass and load, ℓ = N/k.
        Without it Ω is measured from the turning points (Eq. 13-14) and ℓ = 1
        signal unit.
    skip_oscillations : int
        Oscillations after the release left out of the analysis, default 1, as for the
        Bayesian fit (:func:`bayestribo.signal.decay.energy_decay`): the estimators
        and the fit analyse the same window. The analysis needs
        :data:`MIN_TURNING_POINTS` turning points after the skipped ones.
    offset : float, "auto", "constant" or None
        Equilibrium of the displacement (see :func:`bayestribo.signal.peaks.find_peaks`).

    Returns
    -------
    EnergyData

    Raises
    ------
    RecordingError
        No signal, bad samples or time stamps, a bad ``skip_oscillations``, or too
        few turning points.
    """
    if x is None and v is None:
        raise RecordingError("give a displacement x or a velocity v (or both)")
    decay = energy_decay(
        t,
        x,
        v,
        rig=rig,
        use_nominal_frequency=rig is not None and not rig.frequency_measured,
        skip_oscillations=skip_oscillations,
        min_turning_points=MIN_TURNING_POINTS,
        offset=offset,
    )
    energy = decay.energy - sample_noise_bias(decay)
    return EnergyData(
        tau=decay.tau,
        y=decay.y,
        yp=decay.yp,
        energy=energy,
        pi=retrograde_integral(decay.tau, energy),
        tau_end=decay.tau_end,
        omega=decay.scaling.omega,
        length_scale=decay.scaling.length_scale,
        peaks=decay.peaks,
        stopped=decay.motion_ended,
        source=_SOURCES[decay.derived_channel],
        start_time=decay.start_time,
    )


def _model_pi(
    model: Model, mu_s: float | None, y_start: float, yp_start: float
) -> Callable[..., NDArray]:
    """Π of ``model`` from the first analysed sample.

    The analysis starts at the sample nearest a turning point, where the velocity
    ``yp_start`` is small but not zero: the exact model starts from it, on the side
    of ``y_start``; the averaged law describes the envelope only and starts from the
    amplitude.
    """
    from bayestribo.model import averaged_pi, exact_pi

    if model == "averaged":

        def f(tau: NDArray, y0: float, zeta: float, mu: float, tau_end: float) -> NDArray:
            return averaged_pi(tau, y0, zeta, mu, tau_end=tau_end)

    else:
        sign = 1.0 if y_start >= 0.0 else -1.0

        def f(tau: NDArray, y0: float, zeta: float, mu: float, tau_end: float) -> NDArray:
            ms = mu if mu_s is None else max(mu_s, mu)
            return exact_pi(tau, sign * y0, zeta, mu, ms, yp_start, tau_end=tau_end)

    return f


def energy_least_squares(
    t: ArrayLike,
    x: ArrayLike | None = None,
    v: ArrayLike | None = None,
    *,
    rig: Rig | None = None,
    model: Model = "averaged",
    skip_oscillations: int = 1,
    offset: float | Literal["auto", "constant"] | None = "auto",
    mu_s: float | None = None,
    max_points: int = 2000,
    data: EnergyData | None = None,
) -> Estimate:
    """Fit ζ, μ_k and Y_0 to Π(τ) by least squares (the paper's method, Eq. 42).

    Parameters
    ----------
    t, x, v, rig, skip_oscillations, offset
        The recording, as in :func:`energy_data`.
    model : {"averaged", "exact"}
        Π_app of Eq. 40-41 or the exact Π of the piecewise solution.
    mu_s : float, optional
        Static friction of the exact model (default μ_k: stop at the first turning
        point inside ±μ_k).
    max_points : int
        Π is smooth: at most this many evenly spaced samples enter the fit.
    data : EnergyData, optional
        Pre-computed :func:`energy_data` (then t, x, v, skip_oscillations and offset
        are ignored).

    Returns
    -------
    Estimate
        ζ, μ_k (with a loaded rig) and x_c = μ_k ℓ, standard errors from the Jacobian
        covariance (see the module notes: too small), ``delta_pi`` (Eq. 42),
        ``covariance`` over ("zeta", "mu", "y0") in dimensionless units.

    Raises
    ------
    RecordingError
        Bad recording or too few turning points.
    ValueError
        Unknown ``model``.
    """
    if model not in ("averaged", "exact"):
        raise ValueError(f"model must be 'averaged' or 'exact', got {model!r}")
    if isinstance(max_points, bool) or not isinstance(max_points, int) or max_points < 10:
        raise ValueError(f"max_points must be an integer >= 10, got {max_points!r}")
    if data is None:
        data = energy_data(t, x, v, rig=rig, skip_oscillations=skip_oscillations, offset=offset)
    pk = data.peaks
    ell = data.length_scale
    n = data.tau.size
    idx = np.unique(np.linspace(0, n - 1, min(n, max_points)).round().astype(int))
    tau = data.tau[idx]
    pi_exp = data.pi[idx]
    y0 = abs(float(pk.value[0])) / ell

    # starting point: Feeny-Liang on the same peaks, kept inside the model's domain
    try:
        fl = feeny_liang(pk, rig) if len(pk) >= 4 else None
    except RecordingError:
        fl = None
    z0 = fl.zeta if fl is not None and fl.zeta is not None else 0.01
    m0 = fl.friction_displacement / ell if fl is not None else 0.0
    z0 = min(max(z0, 1e-4), 0.5)
    m0 = min(max(m0, 1e-4 * y0), 0.5 * y0)
    f = _model_pi(model, mu_s, float(data.y[0]), float(data.yp[0]))

    def resid(p: NDArray) -> NDArray:
        return f(tau, p[2], p[0], p[1], data.tau_end) - pi_exp

    lower = [0.0, 0.0, 0.5 * y0]
    upper = [0.99, y0, 2.0 * y0]
    sol = scipy.optimize.least_squares(
        resid,
        [z0, m0, y0],
        bounds=(lower, upper),
        x_scale=[max(z0, 1e-3), max(m0, 1e-3 * y0), y0],
        xtol=1e-12,
        ftol=1e-12,
        gtol=1e-12,
        max_nfev=2000,
    )
    zeta, mu, amp = (float(v_) for v_ in sol.x)
    res = sol.fun
    delta_pi = float(math.sqrt(np.mean(res**2)))
    cov = None
    se = [None, None, None]
    if tau.size > 3:
        s2 = float(np.sum(res**2)) / (tau.size - 3)
        try:
            cov = np.linalg.inv(sol.jac.T @ sol.jac) * s2
            se = [math.sqrt(max(cov[i, i], 0.0)) for i in range(3)]
        except np.linalg.LinAlgError:
            cov = None
    notes = [f"{model} Π model", "SE from the Jacobian with correlated residuals: too small"]
    if model == "averaged":
        notes.insert(1, "Eq. 41 corrected: A = (Γ²/ζ)(3/4 - ½ ln(Γ/Λ))")
    for name, val, lo, hi, scale in zip(
        ("ζ", "μ", "Y_0"), sol.x, lower, upper, (1e-6, 1e-6 * y0, 1e-6 * y0), strict=True
    ):
        if val <= lo + scale or val >= hi - scale:
            notes.append(f"{name} at its bound {lo if val <= lo + scale else hi:.3g}")
    if not sol.success:
        notes.append(f"optimiser: {sol.message}")
    scaling = rig.scaling() if rig is not None else None
    mu_k = mu_se = None
    if scaling is not None and scaling.friction_defined:
        mu_k, mu_se = mu, se[1]
    a_end = 0.0 if data.stopped else abs(float(pk.value[-1])) / ell
    share = friction_fraction(zeta, mu, amp, a_end) if amp > a_end else None
    return Estimate(
        method=f"energy_ls_{model}",
        zeta=zeta,
        zeta_se=se[0],
        mu_k=mu_k,
        mu_k_se=mu_se,
        friction_displacement=mu * ell,
        friction_displacement_se=None if se[1] is None else se[1] * ell,
        data=f"Π over {tau.size} of {n} samples ({data.source})",
        notes="; ".join(notes),
        delta_pi=delta_pi,
        covariance=cov,
        parameters=("zeta", "mu", "y0"),
        friction_fraction=share,
        details={
            "y0": amp,
            "y0_se": se[2],
            "tau_end": data.tau_end,
            "omega": data.omega,
            "length_scale": ell,
            "stopped": data.stopped,
            "nfev": int(sol.nfev),
        },
    )
