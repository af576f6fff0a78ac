"""Feeny-Liang successive-peak decrement (Rigaud et al. 2010, Eq. 20-21).

Derivation (checked in the tests against exact responses). From Eq. 16 at
τ_{n+1} = τ_n + π/ω, where cos = -1 and sin = 0, with r = exp(-βπ) (Eq. 13-14):

    Y_{n+1} = -r Y_n + μ_k sgn(Y_n)(1 + r)                                   (Eq. 20)

Since the signs alternate, the sums S_n = Y_n + Y_{n+1} obey S_{n+1} = -r S_n, so
S_{2p} = r^{2p} S_0 and

    β = -1/(2pπ) ln((Y_{2p} + Y_{2p+1})/(Y_0 + Y_1))                         (Eq. 21)

**Correction to Eq. 21 as printed:** the scan reads ln((-Y_{2p} - Y_{2p+1})/(Y_0 + Y_1)),
whose argument is negative (S_{2p} has the sign of S_0); the minus signs do not belong.

Velocity peaks ("-Y'_k in place of Y_k", section 1.6): the velocity extremum of the
half-cycle after turning point n is Y'_n = -K (Y_n - μ_k sgn Y_n) with
K = exp(-β atan(1/β)) (from Eq. 17), so A_n = -Y'_n/K obeys
A_{n+1} = -r A_n + 2 μ_k sgn(A_n): the sums decay as above (same β), but μ_k comes
from the factor 2 instead of 1 + r. Using Eq. 20 literally on -Y'_k would give
μ_k K·2/(1+r) = μ_k (1 + O(β²)); this module applies the exact factor.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.optimize

from bayestribo.errors import RecordingError
from bayestribo.estimators._common import (
    alternating_sign,
    check_peaks,
    describe,
    friction_factor,
    length_amplitudes,
    make_estimate,
    omega,
    zeta_from_beta,
)
from bayestribo.estimators.result import Estimate
from bayestribo.model.scaling import Rig
from bayestribo.signal.peaks import Peaks

__all__ = ["feeny_liang", "friction_from_beta"]


def friction_from_beta(peaks: Peaks, beta: float, omega_: float) -> tuple[float, float | None]:
    """Friction displacement x_c from Eq. 20 given β, averaged over all successive pairs.

    Each pair gives b_n = s_n (Z_{n+1} + r Z_n) = r|Z_n| - |Z_{n+1}| with
    b = x_c(1 + r) for displacement peaks and b = 2 x_c for velocity peaks.

    Returns
    -------
    xc : float
        Friction displacement [signal length unit].
    se : float or None
        Standard error from the scatter of the pairs (they share peaks, so this is a
        rough figure); None with a single pair.
    """
    z = length_amplitudes(peaks, beta, omega_)
    s = alternating_sign(peaks)
    r = math.exp(-beta * math.pi)
    b = s[:-1] * (z[1:] + r * z[:-1]) / friction_factor(peaks.kind, r)
    se = float(np.std(b, ddof=1) / math.sqrt(b.size)) if b.size > 1 else None
    return float(np.mean(b)), se


def feeny_liang(peaks: Peaks, rig: Rig | None = None, p: int | None = None) -> Estimate:
    """Successive-peak decrement of Feeny and Liang: β from peak sums, μ_k from Eq. 20.

    Parameters
    ----------
    peaks : Peaks
        Successive turning points (displacement or velocity) about the equilibrium.
    rig : Rig, optional
        Gives Ω and, with load and mass, μ_k = x_c k/N; without it Ω comes from the
        peak spacing and friction is reported as the friction displacement x_c.
    p : int, optional
        Use Eq. 21 with this p (needs 2p + 2 peaks). By default β is the
        least-squares fit of S_{2j} = S_0 exp(-2πβ j) over all non-overlapping sums
        S_{2j} = Y_{2j} + Y_{2j+1} (Eq. 21 for every p at once).

    Returns
    -------
    Estimate
        ζ (Eq. 14), x_c and μ_k (Eq. 20) with standard errors (β: Jacobian of the
        fit; x_c: scatter of the pairs). No standard error for ζ with ``p`` given.
    """
    z = peaks.amplitudes() if len(peaks) else np.empty(0)
    if p is not None:
        if isinstance(p, bool) or int(p) != p or p < 1:
            raise RecordingError(f"feeny_liang: p must be an integer >= 1, got {p!r}")
        p = int(p)
        check_peaks(peaks, 2 * p + 2, f"feeny_liang (p={p})")
        ratio = (z[2 * p] + z[2 * p + 1]) / (z[0] + z[1])
        if not ratio > 0:
            raise RecordingError(
                f"feeny_liang: (Y_2p + Y_2p+1)/(Y_0 + Y_1) = {ratio:.3g} is not positive "
                f"(p={p}): the peak sums are lost in the noise or the offset is wrong"
            )
        beta = -math.log(ratio) / (2 * p * math.pi)
        beta_se = None
        data = describe(peaks, f"Eq. 21 with p={p}")
    else:
        check_peaks(peaks, 4, "feeny_liang")
        n_sums = z.size // 2
        sums = z[0 : 2 * n_sums : 2] + z[1 : 2 * n_sums : 2]
        j = np.arange(n_sums, dtype=float)
        if sums[-1] / sums[0] > 0:
            beta0 = -math.log(sums[-1] / sums[0]) / (2 * math.pi * j[-1])
        else:
            beta0 = 0.0

        def resid(q: np.ndarray) -> np.ndarray:
            return q[0] * np.exp(-2.0 * math.pi * q[1] * j) - sums

        sol = scipy.optimize.least_squares(resid, [sums[0], beta0], method="lm")
        beta = float(sol.x[1])
        beta_se = None
        if n_sums > 2:
            s2 = float(np.sum(sol.fun**2)) / (n_sums - 2)
            try:
                cov = np.linalg.inv(sol.jac.T @ sol.jac) * s2
                beta_se = math.sqrt(max(cov[1, 1], 0.0))
            except np.linalg.LinAlgError:
                beta_se = None
        data = describe(peaks, f"{n_sums} peak sums")
    notes = (
        "Eq. 21 sign corrected; exact velocity-peak factor"
        if peaks.kind == "velocity"
        else ("Eq. 21 sign corrected")
    )
    if beta < 0:
        notes += "; β < 0: the viscous part is below what the peaks resolve"
    w = omega(peaks, rig, zeta_from_beta(beta))
    xc, xc_se = friction_from_beta(peaks, beta, w)
    return make_estimate(
        "feeny_liang",
        peaks,
        rig,
        beta=beta,
        beta_se=beta_se,
        xc=xc,
        xc_se=xc_se,
        omega_=w,
        data=data,
        notes=notes,
        details={"p": p},
    )
