r"""Stretches of an analysed decay and the least-squares fit of one stretch.

A *segment* is a stretch of an :class:`bayestribo.signal.decay.EnergyDecay` that starts at a
displacement turning point (y' = 0, the initial state of Eq. 15) and ends at a later
turning point, or at the end of the analysed decay. The same fit serves the whole
decay (one segment) and each window of the windowed analysis (section 3.1 of the
paper, after Wu et al. 2007).

The fit maximises the likelihood the Bayesian fit uses: the retrograde integral
Π (Eq. 39) restricted to the segment, observed on a grid as independent increments
``D_j = ∫_{τ_j}^{τ_{j+1}} E dτ``, each with the variance its measurement noise gives
it: the quadrature weights, the noise bias and the increment variances are those of
:mod:`bayestribo.signal.increments`, on a finer grid
(:data:`INCREMENTS_PER_HALF_CYCLE`), against the same increments of the exact
model's Π (:func:`bayestribo.model.exact_pi`, started at the segment's first turning
point with amplitude Y_0 fitted, μ_s = μ_k). The free parameters are ζ, the
dimensionless friction μ (μ_k with a loaded rig, else the friction displacement in
signal units) and Y_0.

On a nonlinear restoring force (a decay whose ``restoring`` is set: a pendulum, a
Duffing spring, docs/restoring.md) the energy is ½y'² + V(y) and the model's Π is that
of viscous damping and Coulomb friction on the force, from the law's integrator
(:meth:`bayestribo.model.laws.Law.pi_grid`, :mod:`bayestribo.adequacy.restoring`).

Noise: :func:`bayestribo.signal.increments.increment_noise`, white per channel when
both are recorded, propagated by Monte Carlo through the derivation of a derived
channel.

Uncertainty. The covariance is the inverse Fisher information of the increments,
``(JᵀWJ)⁻¹``, multiplied by the reduced χ² of the fit when that exceeds one (a
model that does not describe the data within its noise widens its own intervals
instead of claiming a precision it does not have). Intervals are Gaussian,
labelled as such.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.optimize
from numpy.typing import NDArray

from bayestribo.errors import RecordingError
from bayestribo.signal.decay import EnergyDecay
from bayestribo.signal.increments import (
    increment_draws,
    increment_noise,
    increment_weights,
    integrate_increments,
)

__all__ = [
    "PARAMETERS",
    "SegmentFit",
    "fit_segment",
    "peak_positions",
    "segment_noise",
    "whole_decay_fit",
]

#: Names of the fitted parameters, in the order of the covariance.
PARAMETERS: tuple[str, str, str] = ("zeta", "mu", "y0")

#: Increments per half cycle of the observation grid (an even number of samples each).
INCREMENTS_PER_HALF_CYCLE = 8

#: Monte Carlo replicates used to propagate the noise through a derivative filter.
NOISE_REPLICATES = 200


@dataclass(frozen=True)
class SegmentFit:
    """Least-squares fit of ζ, μ and Y_0 to one stretch of a decay.

    Attributes
    ----------
    zeta, mu, y0 : float
        Estimates: viscous damping ζ [-], friction μ [-] (μ_k with a loaded rig,
        else the friction displacement in signal units, since ℓ = 1) and the
        amplitude Y_0 of the segment's first turning point [-].
    covariance : ndarray
        3×3 covariance of (ζ, μ, Y_0), inflated by ``chi2_reduced`` when above 1.
    chi2_reduced : float
        χ² of the increments over their degrees of freedom.
    n_increments : int
        Number of Π increments fitted.
    tau_start, tau_end : float
        Segment limits on the decay's τ axis [-].
    at_bound : tuple of str
        Parameters whose estimate sits on a bound (e.g. μ = 0); their Gaussian
        interval is one-sided in truth.
    notes : str
        Optimiser messages, if any.
    """

    zeta: float
    mu: float
    y0: float
    covariance: NDArray
    chi2_reduced: float
    n_increments: int
    tau_start: float
    tau_end: float
    at_bound: tuple[str, ...] = ()
    notes: str = ""
    extra: dict[str, Any] = field(default_factory=dict)

    def se(self, name: str) -> float:
        """Standard error of ``name`` (one of :data:`PARAMETERS`)."""
        i = PARAMETERS.index(name)
        return math.sqrt(max(float(self.covariance[i, i]), 0.0))

    @property
    def values(self) -> NDArray:
        """(ζ, μ, Y_0) as an array."""
        return np.array([self.zeta, self.mu, self.y0])


def peak_positions(decay: EnergyDecay) -> NDArray:
    """Sample index in the decay's arrays of each displacement turning point."""
    idx = np.asarray(decay.peaks.index, dtype=int)
    if idx.size and idx[0] >= 0:
        pos = idx - idx[0]
    else:
        pos = np.searchsorted(decay.t, decay.peaks.t)
    return np.clip(pos, 0, decay.t.size - 1)


@dataclass(frozen=True)
class _Noise:
    sigma_y: float
    sigma_yp: float
    derived: str | None
    savgol_window: int | None


def segment_noise(decay: EnergyDecay) -> _Noise:
    """Noise levels of a decay in units of y and y', with how the channels were made."""
    sy = decay.noise_y
    syp = decay.noise_yp
    if sy is None and syp is None:
        raise RecordingError("the decay has no noise level on either channel")
    return _Noise(
        sigma_y=0.0 if sy is None else float(sy),
        sigma_yp=0.0 if syp is None else float(syp),
        derived=decay.derived_channel,
        savgol_window=decay.savgol_window,
    )


def _observed(
    tau: NDArray,
    y: NDArray,
    yp: NDArray,
    noise: _Noise,
    n_increments: int,
    seed: int,
    restoring: Any = None,
    keep_draws: bool = False,
) -> tuple[NDArray, NDArray, NDArray, NDArray | None]:
    """Grid edges, observed increments (bias-corrected) and their noise variances, of
    the energy ½(y² + y'²), or ½y'² + V(y) on a nonlinear ``restoring`` force (whose
    noise takes V'(y) for y, or V itself in the Monte Carlo of a derived channel), and
    with ``keep_draws`` (a derived channel) the Monte Carlo's draws of the increments'
    noise, shape (replicates, increments)."""
    h = float(tau[1] - tau[0])
    edges, weights = increment_weights(tau.size, h, n_increments)
    force, potential = y, None
    if restoring is not None and noise.derived is not None:
        potential = restoring.potential
    elif restoring is not None:
        force = np.asarray(restoring.spring(y), dtype=float)
    args = (tau, force, yp, edges, weights, noise.sigma_y, noise.sigma_yp)
    options = {
        "derived": noise.derived,
        "savgol_window": noise.savgol_window,
        "n_replicates": NOISE_REPLICATES,
        "seed": seed,
        "potential": potential,
    }
    draws = None
    if keep_draws and noise.derived is not None:
        draws = increment_draws(*args, **options)
        bias, var = draws.mean(axis=0), draws.var(axis=0, ddof=1)
    else:
        bias, var = increment_noise(*args, **options)
    if restoring is None:
        energy = 0.5 * (y * y + yp * yp)
    else:
        energy = 0.5 * yp * yp + np.asarray(restoring.potential(y), dtype=float)
    obs = integrate_increments(energy, edges, weights) - bias
    floor = 1e-12 * max(float(np.max(var)), 1e-300)
    return edges, obs, np.maximum(var, floor), draws


def _start_values(peaks_abs: NDArray) -> tuple[float, float]:
    """ζ and μ from the successive-peak regression A_{n+1} = r A_n - (1+r)μ (Eq. 20)."""
    if peaks_abs.size >= 3:
        r, c = np.polyfit(peaks_abs[:-1], peaks_abs[1:], 1)
        if 0.0 < r < 1.0:
            beta = -math.log(r) / math.pi
            return beta / math.sqrt(1.0 + beta * beta), max(-c / (1.0 + r), 0.0)
    if peaks_abs.size >= 2 and peaks_abs[1] < peaks_abs[0]:
        beta = -math.log(peaks_abs[1] / peaks_abs[0]) / math.pi
        return beta / math.sqrt(1.0 + beta * beta), 0.0
    return 0.01, 0.0


def _rest_pi(
    tau: NDArray, y0: float, zeta: float, mu: float, yp0: float, tau_end: float
) -> NDArray:
    """∫_τ^{τ_end} E of the pin at rest: the energy ½y_rest² from the model's stop to
    the segment's end, 0 when it does not stop before.

    The model's Π (:func:`bayestribo.model.exact_pi`) runs to the stop and leaves the
    rest out, but a segment that ends at the end of motion holds the sample after the
    stop, and its last increment the energy at rest up to it (about ½y_rest² times a
    sample's step): 4 % of that increment on the paper's rig, thousands of its noise sd
    on a velocity-only record, whose windows' fit then bends ζ and μ in the last window.
    """
    from bayestribo.model import rest_position, stop_time

    stop = float(stop_time(y0, zeta, mu, mu, yp0))
    if not stop < tau_end:
        return np.zeros_like(tau)
    rest = float(rest_position(y0, zeta, mu, mu, yp0))
    return 0.5 * rest * rest * np.clip(tau_end - np.maximum(tau, stop), 0.0, None)


def fit_segment(
    decay: EnergyDecay,
    start: int,
    stop: int,
    peaks_abs: NDArray,
    *,
    noise: _Noise | None = None,
    seed: int = 0,
    fixed_mu: float | None = None,
    free_offset: bool = False,
    rest_energy: bool = False,
) -> SegmentFit:
    """Fit ζ, μ and Y_0 to the Π increments of samples ``start:stop`` of a decay.

    Parameters
    ----------
    decay : EnergyDecay
        The analysed decay.
    start, stop : int
        Sample range in the decay's arrays; ``start`` must be a turning point.
    peaks_abs : ndarray
        |Y_n| of the turning points inside the segment (dimensionless), first one
        at ``start``: starting values and the bound on μ.
    noise : optional
        Pre-computed :func:`segment_noise` of the decay.
    seed : int
        Seed of the noise propagation for a derived channel.
    fixed_mu : float, optional
        Hold μ at this value (dimensionless) and fit ζ and Y_0 only: the
        *equivalent* damping of the segment, all of its dissipation beyond that
        friction counted as viscous. Its row and column of the covariance are 0.
    free_offset : bool
        Fit an offset δ of the segment's displacement from the decay's equilibrium
        as well (the energy taken as ½((y - δ)² + y'²)), a nuisance parameter whose
        uncertainty the covariance of (ζ, μ, Y_0) includes: for a displacement
        integrated from the velocity, whose integration constant wanders along the
        record with the integrated noise. The covariance is then the Monte Carlo's
        of the estimates (each draw of the increments' noise through the
        least-squares step), widened by the reduced χ² beyond what the draws give it.
    rest_energy : bool
        Count the energy of the pin at rest from the model's stop to the segment's end
        in the model's Π (:func:`_rest_pi`), as the observed increments count it. Below
        the noise of a recorded displacement (there the fit is left as it was); on a
        velocity-only record thousands of the last increment's sd.

    Returns
    -------
    SegmentFit

    Raises
    ------
    RecordingError
        A segment too short to fit (fewer than 8 increments).
    """
    from bayestribo.model import exact_pi

    law = None
    if decay.restoring is not None:
        from bayestribo.adequacy.restoring import segment_law

        law = segment_law(decay.restoring)
    noise = segment_noise(decay) if noise is None else noise
    tau = decay.tau[start:stop] - decay.tau[start]
    y, yp = decay.y[start:stop], decay.yp[start:stop]
    if peaks_abs.size < 2 or tau.size < 16:
        raise RecordingError(
            f"a segment of {tau.size} samples and {peaks_abs.size} turning points is too "
            "short to fit; use a longer window"
        )
    n_increments = INCREMENTS_PER_HALF_CYCLE * max(peaks_abs.size - 1, 1)
    edges, obs, var, draws = _observed(
        tau, y, yp, noise, n_increments, seed, decay.restoring, keep_draws=free_offset
    )
    if edges.size < 9:
        raise RecordingError(
            f"a segment with {edges.size - 1} Π increments is too short to fit; use a longer window"
        )
    sd = np.sqrt(var)
    tau_e = tau[edges]
    tau_end = float(tau[-1])
    amp = float(peaks_abs[0])
    sign = 1.0 if y[0] >= 0.0 else -1.0
    yp0 = float(yp[0])  # the sample nearest the turning point is not exactly on it
    z0, m0 = _start_values(peaks_abs)
    z0 = min(max(z0, 1e-4), 0.5)
    m0 = min(max(m0, 1e-4 * amp), 0.5 * amp)

    free = np.array([True, fixed_mu is None, True])
    if fixed_mu is not None:
        if not (math.isfinite(fixed_mu) and 0.0 <= fixed_mu < amp):
            raise RecordingError(f"fixed_mu must be in [0, {amp:.6g}), got {fixed_mu!r}")
        m0 = float(fixed_mu)

    def full(q: NDArray) -> NDArray:
        p = np.array([z0, m0, amp])
        p[free] = q
        return p

    def model_pi(p: NDArray) -> NDArray:
        if law is None:
            pi = exact_pi(tau_e, sign * p[2], p[0], p[1], p[1], yp0, tau_end=tau_end)
            if rest_energy:
                pi = pi + _rest_pi(tau_e, sign * p[2], p[0], p[1], yp0, tau_end)
            return pi
        values = {"zeta": p[0], "mu_k": p[1], "mu_s_ratio": 1.0}
        return law.pi_grid(tau_e, values, [sign * p[2]], yp0, tau_end, reference=amp)[0]

    n_core = int(np.count_nonzero(free))
    if free_offset:
        # ∫(y - δ)²/2 = ∫y²/2 - δ∫y + δ²∫1/2 over each increment
        _, weights = increment_weights(tau.size, float(tau[1] - tau[0]), n_increments)
        int_y = integrate_increments(y, edges, weights)
        int_1 = integrate_increments(np.ones_like(y), edges, weights)

    def resid(q: NDArray) -> NDArray:
        pi = model_pi(full(q[:n_core]))
        observed = obs
        if free_offset:
            delta = q[n_core]
            observed = obs - delta * int_y + 0.5 * delta * delta * int_1
        return (pi[:-1] - pi[1:] - observed) / sd

    lower = np.array([0.0, 0.0, 0.5 * amp])
    upper = np.array([0.95, amp, 2.0 * amp])
    scale = np.array([max(z0, 1e-3), max(m0, 1e-3 * amp), amp])
    start_q, low_q, high_q, scale_q = (
        np.array([z0, m0, amp])[free],
        lower[free],
        upper[free],
        scale[free],
    )
    if free_offset:
        start_q = np.append(start_q, 0.0)
        low_q = np.append(low_q, -0.5 * amp)
        high_q = np.append(high_q, 0.5 * amp)
        scale_q = np.append(scale_q, 1e-3 * amp)
    sol = scipy.optimize.least_squares(
        resid,
        start_q,
        bounds=(low_q, high_q),
        x_scale=scale_q,
        xtol=1e-10,
        ftol=1e-10,
        gtol=1e-10,
        max_nfev=500,
    )
    n = obs.size
    n_free = sol.x.size
    chi2 = float(np.sum(sol.fun**2))
    red = chi2 / max(n - n_free, 1)
    jac = sol.jac
    inverse = np.linalg.pinv(jac.T @ jac)
    widen = max(red, 1.0)
    if draws is None:
        full_cov = inverse
    else:
        # the estimates' own Monte Carlo: each draw of the increments' noise moves them
        # by the least-squares step (JᵀJ)⁻¹Jᵀ (in sd units), the increments' correlation
        # (an integrated channel's) included, which the inverse alone leaves out; and
        # the reduced χ² is widened for only beyond what the same draws give it
        noise_sd = (draws - draws.mean(axis=0)) / sd
        steps = noise_sd @ (jac @ inverse.T)
        full_cov = np.atleast_2d(np.cov(steps, rowvar=False))
        left = noise_sd - steps @ jac.T
        expected = float(np.mean(np.sum(left * left, axis=1))) / max(n - n_free, 1)
        widen = max(red / expected, 1.0) if expected > 0.0 else widen
    cov = np.zeros((3, 3))
    # the offset's row and column dropped: the marginal covariance of (ζ, μ, Y_0)
    cov[np.ix_(free, free)] = (full_cov * widen)[:n_core, :n_core]
    x = full(sol.x[:n_core])
    tol = 1e-6 * np.array([1.0, amp, amp])
    at_bound = tuple(
        name
        for name, v, lo, hi, t, f in zip(PARAMETERS, x, lower, upper, tol, free, strict=True)
        if f and (v <= lo + t or v >= hi - t)
    )
    return SegmentFit(
        zeta=float(x[0]),
        mu=float(x[1]),
        y0=float(x[2]),
        covariance=cov,
        chi2_reduced=red,
        n_increments=n,
        tau_start=float(decay.tau[start]),
        tau_end=float(decay.tau[stop - 1]),
        at_bound=at_bound,
        notes="" if sol.success else f"optimiser: {sol.message}",
        extra={"fixed_mu": fixed_mu} | ({"offset": float(sol.x[n_core])} if free_offset else {}),
    )


def whole_decay_fit(decay: EnergyDecay, *, seed: int = 0) -> SegmentFit:
    """The same fit on the whole analysed decay (one segment from its first turning point)."""
    peaks_abs = np.abs(decay.peaks.value) / decay.scaling.length_scale
    return fit_segment(decay, 0, decay.t.size, peaks_abs, seed=seed)
