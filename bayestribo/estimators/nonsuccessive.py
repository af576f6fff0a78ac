"""Damping from non-successive peaks Y_0, Y_2p, Y_2q (Rigaud et al. 2010, Eq. 22-25).

Derivation (checked in the tests against exact turning points). With r = exp(-βπ)
and |Y_{n+1}| = r|Y_n| - μ_k(1 + r) (Eq. 20 while the motion goes on),

    |Y_n| = r^n |Y_0| - μ_k (1 + r) Σ_{i=0}^{n-1} r^i,

and for n = 2p, (1 + r) Σ_{i=0}^{2p-1} r^i = 1 + r^{2p} + 2 Σ_{i=1}^{2p-1} r^i, so

    μ_k = (Y_0 r^{2p} - Y_{2p}) / (1 + exp(-2πpβ) + 2 Σ_{i=1}^{2p-1} exp(-iπβ))   (Eq. 24)

for Y_0 > 0 (multiply the numerator by sgn Y_0 otherwise). **Correction to Eq. 23-25
as printed:** the scan shows exp(-2πβ) as the second term of the denominator; it is
exp(-2πpβ) (the two agree only for p = 1, Eq. 22). Eq. 25 equates Eq. 24 for p and q
and is solved for β by a bracketing root finder (Brent) after a scan of β in
[0, β_max] for sign changes.

For velocity peaks, A_n = -Y'_n/K obeys |A_{n+1}| = r|A_n| - 2μ_k, which replaces
(1 + r) by 2 in the denominator: the root β is the same (the factor cancels in
Eq. 25) and μ_k follows with the velocity factor K = exp(-β atan(1/β)).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.optimize

from bayestribo.errors import RecordingError
from bayestribo.estimators._common import (
    check_peaks,
    describe,
    friction_factor,
    make_estimate,
    omega,
    velocity_peak_factor,
    zeta_from_beta,
)
from bayestribo.estimators.result import Estimate
from bayestribo.model.scaling import Rig
from bayestribo.signal.peaks import Peaks

__all__ = ["default_pq", "eq24_friction", "nonsuccessive_peaks"]


def _geometric_sum(beta: float, n: int) -> float:
    """Σ_{i=0}^{n-1} r^i with r = exp(-πβ), stable near β = 0 (value n)."""
    if beta == 0.0:
        return float(n)
    return math.expm1(-n * math.pi * beta) / math.expm1(-math.pi * beta)


def eq24_friction(beta: float, a0: float, a2p: float, p: int, kind: str = "displacement") -> float:
    """μ_k (in the unit of the peaks) from Eq. 24 for given β and |Y_0|, |Y_2p|.

    Parameters
    ----------
    beta : float
        β = ζ/√(1-ζ²) (Eq. 14).
    a0, a2p : float
        |Y_0| and |Y_2p| (same sign for even separation).
    p : int
        Half the peak separation.
    kind : {"displacement", "velocity"}
        Displacement: denominator 1 + r^{2p} + 2Σ r^i = (1 + r)Σ_{i<2p} r^i (corrected
        Eq. 24); velocity amplitudes: 2Σ_{i<2p} r^i.
    """
    r = math.exp(-math.pi * beta)
    den = friction_factor(kind, r) * _geometric_sum(beta, 2 * p)
    return (a0 * math.exp(-2.0 * math.pi * p * beta) - a2p) / den


def default_pq(n_peaks: int) -> tuple[int, int]:
    """Default p < q: Y_2q the last even peak, Y_2p about half-way (very different
    amplitudes, as section 1.6 recommends)."""
    m = (n_peaks - 1) // 2
    if m < 2:
        raise RecordingError(
            f"nonsuccessive_peaks needs Y_0, Y_2p and Y_2q with p < q, i.e. at least 5 "
            f"peaks, got {n_peaks}"
        )
    return max(1, m // 2), m


def _eq25(beta: np.ndarray, a0: float, a2p: float, a2q: float, p: int, q: int) -> np.ndarray:
    """Eq. 25 as μ_p(β) - μ_q(β) on an array of β (the factor 1 + r cancels)."""
    x = np.pi * beta
    with np.errstate(invalid="ignore", divide="ignore"):
        g = np.where(x == 0.0, 1.0, np.expm1(-x))
        gp = np.where(x == 0.0, 2.0 * p, np.expm1(-2 * p * x) / g)
        gq = np.where(x == 0.0, 2.0 * q, np.expm1(-2 * q * x) / g)
    return (a0 * np.exp(-2 * p * x) - a2p) / gp - (a0 * np.exp(-2 * q * x) - a2q) / gq


def _solve(
    a0: float, a2p: float, a2q: float, p: int, q: int, beta_min: float, beta_max: float
) -> list[float]:
    """Roots of Eq. 25: sign changes on a grid of β, each refined by Brent's method."""
    neg = -np.geomspace(-beta_min, 1e-6, 100) if beta_min < 0 else np.empty(0)
    grid = np.concatenate([neg, [0.0], np.geomspace(1e-6, beta_max, 400)])
    vals = _eq25(grid, a0, a2p, a2q, p, q)

    def f(b: float) -> float:
        return float(_eq25(np.array(b), a0, a2p, a2q, p, q))

    out = []
    for i in range(grid.size - 1):
        if vals[i] == 0.0:
            out.append(float(grid[i]))
        elif vals[i] * vals[i + 1] < 0:
            out.append(scipy.optimize.brentq(f, grid[i], grid[i + 1], xtol=1e-14, rtol=1e-12))
    return out


def nonsuccessive_peaks(
    peaks: Peaks,
    rig: Rig | None = None,
    p: int | None = None,
    q: int | None = None,
    *,
    beta_min: float = -0.05,
    beta_max: float = 1.0,
) -> Estimate:
    """β and μ_k from three non-successive peaks Y_0, Y_2p, Y_2q (Eq. 24-25).

    Parameters
    ----------
    peaks : Peaks
        Successive turning points about the equilibrium (displacement or velocity).
    rig : Rig, optional
        Gives Ω and, with load and mass, μ_k = x_c k/N.
    p, q : int, optional
        Distinct integers >= 1 with 2p, 2q < number of peaks. Default
        :func:`default_pq`.
    beta_min, beta_max : float
        The β search interval (β = 1 is ζ ≈ 0.71). It reaches below 0 because with
        noise a negligible viscous part can give a root at a small negative β
        (reported with a note) rather than no root at all.

    Returns
    -------
    Estimate
        ζ, x_c (and μ_k) with standard errors propagated from the noise of the three
        peak values (``peaks.value_noise``) by the implicit-function derivatives.

    Raises
    ------
    RecordingError
        Too few peaks, bad p or q, or Eq. 25 has no root for β in [beta_min, beta_max]
        (the message gives the three peak values).
    """
    check_peaks(peaks, 5, "nonsuccessive_peaks")
    if p is None or q is None:
        dp, dq = default_pq(len(peaks))
        p = dp if p is None else p
        q = dq if q is None else q
    for name, val in (("p", p), ("q", q)):
        if isinstance(val, bool) or int(val) != val or val < 1:
            raise RecordingError(
                f"nonsuccessive_peaks: {name} must be an integer >= 1, got {val!r}"
            )
    p, q = int(p), int(q)
    if p == q:
        raise RecordingError(f"nonsuccessive_peaks: p and q must differ, got p = q = {p}")
    if 2 * max(p, q) >= len(peaks):
        raise RecordingError(
            f"nonsuccessive_peaks: 2·max(p, q) = {2 * max(p, q)} needs more than {len(peaks)} peaks"
        )
    p, q = min(p, q), max(p, q)
    z = peaks.amplitudes()
    s0 = 1.0 if z[0] >= 0 else -1.0
    a0, a2p, a2q = s0 * z[0], s0 * z[2 * p], s0 * z[2 * q]
    if not beta_min < beta_max:
        raise RecordingError(f"need beta_min < beta_max, got {beta_min!r}, {beta_max!r}")
    roots = _solve(a0, a2p, a2q, p, q, beta_min, beta_max)
    if not roots:
        raise RecordingError(
            f"nonsuccessive_peaks: Eq. 25 has no root for β in [{beta_min}, {beta_max}] "
            f"with p={p}, q={q} (Y_0={a0:.6g}, Y_2p={a2p:.6g}, Y_2q={a2q:.6g}): these peaks "
            "are not consistent with viscous + Coulomb damping (noise, offset, or too few "
            "oscillations); try other p and q"
        )
    # several roots: the one nearest β = 0 (the others come from the ends of the range)
    beta = min(roots, key=abs)
    notes = "Eq. 23-25 corrected: exp(-2πpβ) in the denominator"
    if len(roots) > 1:
        notes += f"; {len(roots)} roots in [{beta_min}, {beta_max}], the one nearest 0 is used"
    if beta < 0:
        notes += "; β < 0: the viscous part is below what the peaks resolve"

    # friction in the unit of the peaks (velocity: -Y'_k), then as a length
    mu_peak = eq24_friction(beta, a0, a2p, p, peaks.kind)
    w = omega(peaks, rig, zeta_from_beta(beta))
    to_len = 1.0 / (velocity_peak_factor(beta) * w) if peaks.kind == "velocity" else 1.0
    xc = mu_peak * to_len

    # standard errors: implicit derivatives by finite differences of the root
    sigma = peaks.value_noise
    beta_se = xc_se = None
    if sigma > 0:
        h = max(sigma, 1e-9 * abs(a0))
        d_beta = []
        d_mu = []
        base = [a0, a2p, a2q]
        for k in range(3):
            vals = []
            for sgn in (1.0, -1.0):
                pert = list(base)
                pert[k] += sgn * h
                rr = _solve(*pert, p, q, beta_min, beta_max)
                if not rr:
                    vals = []
                    break
                b = min(rr, key=lambda x: abs(x - beta))
                vals.append((b, eq24_friction(b, pert[0], pert[1], p, peaks.kind)))
            if len(vals) == 2:
                d_beta.append((vals[0][0] - vals[1][0]) / (2 * h))
                d_mu.append((vals[0][1] - vals[1][1]) / (2 * h))
        if len(d_beta) == 3:
            beta_se = sigma * math.sqrt(sum(d * d for d in d_beta))
            xc_se = sigma * math.sqrt(sum(d * d for d in d_mu)) * to_len
    return make_estimate(
        "nonsuccessive",
        peaks,
        rig,
        beta=beta,
        beta_se=beta_se,
        xc=xc,
        xc_se=xc_se,
        omega_=w,
        data=describe(peaks, f"Y_0, Y_{2 * p}, Y_{2 * q}"),
        notes=notes + ("; SE from the peak noise only" if beta_se is not None else ""),
        details={"p": p, "q": q, "roots": roots},
    )
