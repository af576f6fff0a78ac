"""Predictive check on the signals: simulated peaks against the recorded ones.

The paper compares the responses simulated with the identified (ζ, μ_k) with the
measured ones peak by peak (Fig. 8). Here the exact model (Eq. 16-17 with sticking,
:func:`bayestribo.model.turning_points`) is run from the first analysed turning
point for every parameter draw, and each recorded peak is set against its
predictive distribution: the model's value of that peak over the draws plus the
measurement error of a peak value (its noise, and a relative reading error, 0.1 %
by default, for the scale of each channel: sensor calibration and the measured Ω
that turns a velocity into y').

* Displacement peaks |Y_n| (turning points).
* Velocity peaks: the largest |y'| of each half cycle, ``(|Y_n| - μ_k)·e^{-ζ s*}``
  with ``tan(ω s*) = ω/ζ`` (the extremum of Eq. 17's velocity), against the
  recorded extremum (a least-squares parabola over ±1/12 period around the largest
  sample, as :func:`bayestribo.signal.peaks.find_peaks` refines displacement peaks).

A peak the model does not reach (the motion has stopped before it in that draw)
counts as 0 for that draw. The summary numbers are the fraction of recorded peaks
inside their central 95 % predictive interval (about 0.95 for an adequate model)
and the RMS standardized residual (about 1).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.adequacy.draws import ParameterDraws
from bayestribo.adequacy.restoring import chains, first_turn, hermite, rest_grid
from bayestribo.adequacy.segments import peak_positions
from bayestribo.errors import BayestriboError
from bayestribo.signal.decay import EnergyDecay
from bayestribo.signal.peaks import estimate_noise

__all__ = ["PeakResiduals", "PredictiveCheck", "predictive_check"]

#: Relative uncertainty of a peak reading beyond the noise (calibration, Ω): 0.1 %.
RELATIVE_ERROR = 1e-3

#: Samples of the predictive bands of the signals.
BAND_POINTS = 1500


@dataclass(frozen=True)
class PeakResiduals:
    """Recorded peaks against their predictive distribution.

    Attributes
    ----------
    kind : str
        ``"displacement"`` or ``"velocity"``.
    t : ndarray
        Time of each peak [s].
    observed : ndarray
        Recorded peak magnitudes [-] (dimensionless y or y').
    predicted : ndarray
        Predictive mean [-].
    low, high : ndarray
        Central 95 % predictive interval [-].
    sd : ndarray
        Predictive standard deviation [-].
    """

    kind: str
    t: NDArray
    observed: NDArray
    predicted: NDArray
    low: NDArray
    high: NDArray
    sd: NDArray

    @property
    def residual(self) -> NDArray:
        """Observed minus predicted [-]."""
        return self.observed - self.predicted

    @property
    def standardized(self) -> NDArray:
        """Residual over the predictive standard deviation."""
        return self.residual / np.maximum(self.sd, 1e-300)

    @property
    def coverage(self) -> float:
        """Fraction of peaks inside their 95 % predictive interval."""
        return float(np.mean((self.observed >= self.low) & (self.observed <= self.high)))

    @property
    def rms_standardized(self) -> float:
        """RMS of the standardized residuals."""
        return float(math.sqrt(np.mean(self.standardized**2)))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (per-peak arrays as lists)."""
        return {
            "kind": self.kind,
            "n_peaks": int(self.observed.size),
            "coverage_95": self.coverage,
            "rms_standardized_residual": self.rms_standardized,
            "t_s": self.t.tolist(),
            "observed": self.observed.tolist(),
            "predicted": self.predicted.tolist(),
            "low": self.low.tolist(),
            "high": self.high.tolist(),
        }


@dataclass(frozen=True)
class PredictiveCheck:
    """Peak-by-peak predictive check of one decay.

    Attributes
    ----------
    displacement, velocity : PeakResiduals
    band_t : ndarray
        Times of the predictive bands [s].
    y_band, yp_band : ndarray
        2.5 %, 50 % and 97.5 % quantiles of the simulated y and y', shape (3, T).
    label : str
        Origin of the draws.
    integrated : bool
        The displacement was integrated from a velocity recorded alone: its turning
        points are shown but not counted in :attr:`coverage` and
        :attr:`rms_standardized` (the integral's wander, which the windows fit as an
        offset of their own, is not in their predictive intervals; on the
        seismometer's velocity alone, records of the law, 9 of 10 fell below 80 %
        coverage with them counted, 0 of 10 without).
    """

    displacement: PeakResiduals
    velocity: PeakResiduals
    band_t: NDArray
    y_band: NDArray
    yp_band: NDArray
    label: str
    integrated: bool = False

    @property
    def counted(self) -> list[PeakResiduals]:
        """The peaks the check counts: the recorded channels' (the velocity alone when
        the displacement was integrated from it)."""
        return [self.velocity] if self.integrated else [self.displacement, self.velocity]

    @property
    def coverage(self) -> float:
        """Fraction of the counted peaks (:attr:`counted`) inside their 95 % interval."""
        sizes = [k.observed.size for k in self.counted]
        return sum(k.coverage * n for k, n in zip(self.counted, sizes, strict=True)) / sum(sizes)

    @property
    def rms_standardized(self) -> float:
        """RMS standardized residual over the counted peaks (:attr:`counted`)."""
        z = np.concatenate([k.standardized for k in self.counted])
        return float(math.sqrt(np.mean(z * z)))

    @property
    def statement(self) -> str:
        """One plain sentence."""
        d, v = self.displacement, self.velocity
        shares = (
            f"velocity {100 * v.coverage:.0f} % of {v.observed.size}; the displacement's "
            f"{d.observed.size} turning points, integrated from the velocity, not counted: "
            f"{100 * d.coverage:.0f} %"
            if self.integrated
            else f"displacement {100 * d.coverage:.0f} % of {d.observed.size}, "
            f"velocity {100 * v.coverage:.0f} % of {v.observed.size}"
        )
        return (
            f"{100 * self.coverage:.0f} % of the recorded peaks lie inside their 95 % "
            f"predictive interval ({shares}); RMS standardized "
            f"residual {self.rms_standardized:.2g} (about 1 for an adequate model); {self.label}"
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (``counted``: the kinds of peaks the coverage counts)."""
        return {
            "coverage_95": self.coverage,
            "rms_standardized_residual": self.rms_standardized,
            "counted": [k.kind for k in self.counted],
            "displacement": self.displacement.to_dict(),
            "velocity": self.velocity.to_dict(),
            "draws": self.label,
            "statement": self.statement,
        }


def _refined_max(
    t: NDArray, s: NDArray, a: int, b: int, half_width: int
) -> tuple[float, float, int]:
    """Largest |s| in samples a..b refined by a least-squares parabola; (time, value, index)."""
    seg = np.abs(s[a : b + 1])
    i = a + int(np.argmax(seg))
    lo, hi = max(i - half_width, 0), min(i + half_width, s.size - 1)
    if hi - lo < 2:
        return float(t[i]), float(abs(s[i])), i
    tt = t[lo : hi + 1] - t[i]
    c = np.polyfit(tt, np.abs(s[lo : hi + 1]), 2)
    t0 = -c[1] / (2.0 * c[0]) if c[0] < 0.0 else 0.0
    if not tt[0] <= t0 <= tt[-1]:
        return float(t[i]), float(abs(s[i])), i
    return float(t[i] + t0), float(np.polyval(c, t0)), i


def _offsets(t: NDArray, centre: NDArray, t_peak: NDArray, half_width: int) -> NDArray:
    """Times [s] of the samples centre ± half_width relative to each refined extremum."""
    k = np.arange(-half_width, half_width + 1)
    idx = np.clip(np.asarray(centre, dtype=int)[:, None] + k[None, :], 0, t.size - 1)
    return t[idx] - np.asarray(t_peak, dtype=float)[:, None]


def _parabola_peak(x: NDArray, values: NDArray) -> NDArray:
    """Vertex value of least-squares parabolas of ``values`` (D, P, K) over ``x`` (P, K).

    Falls back to the largest sample when the parabola does not open downwards or
    its vertex leaves the fitted span. The P fits are one stacked least-squares solve
    (the columns scaled as :func:`numpy.polyfit` scales them).
    """
    xp = x - np.mean(x, axis=1, keepdims=True)  # (P, K)
    design = np.stack([xp**2, xp, np.ones_like(xp)], axis=-1)  # (P, K, 3)
    scale = np.sqrt(np.sum(design**2, axis=1, keepdims=True))  # (P, 1, 3)
    solve = np.linalg.pinv(design / scale)  # (P, 3, K)
    c = np.einsum("pjk,dpk->jdp", solve, values) / scale[:, 0, :].T[:, None, :]  # (3, D, P)
    with np.errstate(divide="ignore", invalid="ignore"):
        v = -c[1] / (2.0 * c[0])
        peak = c[2] - c[1] ** 2 / (4.0 * c[0])
    ok = (c[0] < 0.0) & (v >= xp[:, 0]) & (v <= xp[:, -1])
    return np.where(ok, peak, np.max(values, axis=2))


def _summaries(
    kind: str,
    t: NDArray,
    observed: NDArray,
    model: NDArray,
    noise: float,
    relative: float,
    rng: np.random.Generator,
) -> PeakResiduals:
    sd = np.sqrt(noise**2 + (relative * model) ** 2)
    sim = model + sd * rng.standard_normal(model.shape)
    lo, hi = np.quantile(sim, [0.025, 0.975], axis=0)
    return PeakResiduals(
        kind=kind,
        t=t,
        observed=observed,
        predicted=np.mean(sim, axis=0),
        low=lo,
        high=hi,
        sd=np.std(sim, axis=0),
    )


def predictive_check(
    decay: EnergyDecay,
    draws: ParameterDraws,
    *,
    seed: int | None = 0,
    relative_error: float = RELATIVE_ERROR,
) -> PredictiveCheck:
    """Peak-by-peak predictive check of the exact model with parameter draws.

    Parameters
    ----------
    decay : EnergyDecay
        The analysed decay (its first turning point is the draws' initial state).
    draws : ParameterDraws
        Posterior draws or the labelled Gaussian stand-in.
    seed : int, optional
        Seed of the simulated measurement noise.
    relative_error : float
        Relative standard uncertainty of a recorded peak beyond its noise [-]:
        the scale of each channel (sensor calibration, and the measured Ω that
        turns a velocity into y'). Default 0.1 %.

    Returns
    -------
    PredictiveCheck
    """
    from bayestribo.model import exact_response

    if not (math.isfinite(relative_error) and relative_error >= 0.0):
        raise BayestriboError(
            f"relative_error must be a finite number >= 0, got {relative_error!r}"
        )
    rng = np.random.default_rng(seed)
    ell = decay.scaling.length_scale
    pos = peak_positions(decay)
    n = pos.size
    y_obs = np.abs(decay.peaks.value) / ell
    sign0 = 1.0 if decay.peaks.value[0] >= 0.0 else -1.0

    # recorded velocity extrema of each half cycle
    dt = float(np.median(np.diff(decay.t)))
    half_width = max(1, round(2.0 * decay.peaks.half_period / dt / 12.0))
    v_t, v_obs, v_i = [], [], []
    for a, b in itertools.pairwise(pos):
        tv, vv, iv = _refined_max(decay.t, decay.yp, int(a), int(b), half_width)
        v_t.append(tv)
        v_obs.append(vv)
        v_i.append(iv)

    sign_seq = sign0 * (-1.0) ** np.arange(n)
    # Model peaks processed like the recorded ones: each draw's signal is evaluated
    # at the recorded samples' offsets from the recorded extremum, placed about the
    # draw's own extremum, and refined by the same parabola (the parabola's bias and
    # the sampling phase then affect both alike).
    offsets_y = _offsets(decay.t, pos, decay.peaks.t, half_width) * decay.scaling.omega
    offsets_v = _offsets(decay.t, np.array(v_i), np.array(v_t), half_width) * decay.scaling.omega
    if decay.restoring is None:
        # the peaks from the turning point before the decay's first sample, where the
        # fits start the model (at y0 with the recorded velocity)
        turned = first_turn(decay, draws)[0]
        model_y, model_v, _ = _linear_peaks(turned, n, sign0, sign_seq, offsets_y, offsets_v)
    else:
        model_y, model_v = _restoring_peaks(decay, draws, n, sign0, offsets_y, offsets_v)

    noise_y = decay.peaks.value_noise / ell
    sd_yp = decay.noise_yp if decay.noise_yp else estimate_noise(decay.yp)
    noise_v = float(sd_yp) * math.sqrt(9.0 / 4.0 / (2 * half_width + 1))
    disp = _summaries("displacement", decay.peaks.t, y_obs, model_y, noise_y, relative_error, rng)
    vel = _summaries(
        "velocity", np.array(v_t), np.array(v_obs), model_v, noise_v, relative_error, rng
    )

    idx = np.unique(np.linspace(0, decay.tau.size - 1, BAND_POINTS).round().astype(int))
    tau = decay.tau[idx] - decay.tau[0]
    if decay.restoring is None:
        y_sim, yp_sim = exact_response(
            tau,
            (1.0 if decay.y[0] >= 0.0 else -1.0) * np.abs(draws.y0)[:, None],
            draws.zeta[:, None],
            draws.mu[:, None],
            np.maximum(draws.mu_s, draws.mu)[:, None],
            float(decay.yp[0]),
        )
    else:
        y_sim, yp_sim = _restoring_band(decay, draws, sign0, tau)
    q = [0.025, 0.5, 0.975]
    return PredictiveCheck(
        displacement=disp,
        velocity=vel,
        band_t=decay.t[idx],
        y_band=np.quantile(y_sim, q, axis=0),
        yp_band=np.quantile(yp_sim, q, axis=0),
        label=draws.label,
        integrated=decay.derived_channel == "displacement",
    )


def _linear_peaks(
    draws: ParameterDraws,
    n: int,
    sign0: float,
    sign_seq: NDArray,
    offsets_y: NDArray,
    offsets_v: NDArray,
) -> tuple[NDArray, NDArray, NDArray]:
    """The draws' processed peaks (D, n) and (D, n - 1) on the linear spring (Eq. 16-17),
    and their initial state (D, 1)."""
    from bayestribo.model import exact_response

    z = draws.zeta[:, None]
    m = draws.mu[:, None]
    ms = np.maximum(draws.mu_s, draws.mu)[:, None]
    y_start = np.asarray(draws.y0, dtype=float)
    w = np.sqrt(1.0 - z * z)
    half = np.pi / w
    k = np.arange(n)[None, :]
    tau_y = np.maximum(np.maximum(k * half, 0.0)[:, :, None] + offsets_y[None, :, :], 0.0)
    s_star = np.arctan2(w, z) / w
    tau_v = (np.arange(n - 1)[None, :] * half + s_star)[:, :, None] + offsets_v[None, :, :]
    tau_v = np.maximum(tau_v, 0.0)
    z3, m3, ms3 = z[:, :, None], m[:, :, None], ms[:, :, None]

    def processed_displacement(start: NDArray) -> NDArray:
        y_sim, _ = exact_response(tau_y, sign0 * start[:, None, None], z3, m3, ms3)
        return np.maximum(_parabola_peak(offsets_y, y_sim * sign_seq[None, :, None]), 0.0)

    model_y = processed_displacement(y_start)
    a0 = sign0 * y_start[:, None]
    _, v_sim = exact_response(tau_v, a0[:, :, None], z3, m3, ms3)
    model_v = np.maximum(_parabola_peak(offsets_v, -v_sim * sign_seq[None, :-1, None]), 0.0)

    return model_y, model_v, a0


def _restoring_peaks(
    decay: EnergyDecay,
    draws: ParameterDraws,
    n: int,
    sign0: float,
    offsets_y: NDArray,
    offsets_v: NDArray,
) -> tuple[NDArray, NDArray]:
    """The draws' processed peaks (D, n) and (D, n - 1) on the decay's nonlinear
    restoring force: the turning points from the law's integrator, the motion about
    each (the samples' offsets) from rest there (:func:`~bayestribo.adequacy.restoring.
    rest_grid`); a peak a draw does not reach (stopped before it) is 0."""
    kernel = decay.restoring
    zeta, mu = draws.zeta[:, None], draws.mu[:, None]
    chain = chains(kernel, first_turn(decay, draws)[0], sign0, math.inf, n)
    d = len(chain)
    turns = np.full((d, n), np.nan)
    stuck = np.zeros((d, n), dtype=bool)
    for i, (_, yn, stopped) in enumerate(chain):
        turns[i, : yn.size] = yn
        if stopped:
            stuck[i, yn.size - 1] = True
    reached = np.isfinite(turns)
    start = np.where(reached, turns, 0.0)
    outward = np.sign(start)  # the direction of the motion that arrives at each turn
    # displacement about each turning point: back along the motion that arrived, on
    # along the next half cycle (at rest where the draw stops)
    off = np.broadcast_to(offsets_y[None, :, :], (d, *offsets_y.shape))
    column = np.broadcast_to(np.arange(d * n).reshape(d, n, 1), off.shape)
    h, y, yp, _ = rest_grid(
        kernel.spring, start, -outward, zeta, mu, max(float(np.max(offsets_y)), 0.0)
    )
    on = hermite(h, y.reshape(y.shape[0], -1), yp.reshape(y.shape[0], -1), off, column)
    h, y, yp, _ = rest_grid(
        kernel.spring, start, outward, zeta, mu, min(float(np.min(offsets_y)), 0.0)
    )
    back = hermite(h, y.reshape(y.shape[0], -1), yp.reshape(y.shape[0], -1), off, column)
    y = np.where(off < 0.0, back, np.where(stuck[:, :, None], start[:, :, None], on))
    model_y = np.maximum(_parabola_peak(offsets_y, y * outward[:, :, None]), 0.0)
    model_y = np.where(reached, model_y, 0.0)
    # the velocity's extremum of each half cycle: where y'' = 0 (linear interpolation
    # between grid points), then y' about it
    moving = reached[:, :-1] & reached[:, 1:] & ~stuck[:, :-1]
    first, sgn = start[:, :-1], -outward[:, :-1]
    ratio = np.asarray(kernel.half_period_ratio(np.abs(first)), dtype=float)
    span = 0.75 * math.pi * float(np.max(ratio, initial=1.0)) + float(np.max(offsets_v))
    h, _, yp, ypp = rest_grid(kernel.spring, first, sgn, zeta, mu, span)
    flipped = np.sign(ypp) != sgn[None]  # past the extremum: the acceleration turned
    k = np.clip(np.argmax(flipped, axis=0), 1, ypp.shape[0] - 1)
    a_lo = np.take_along_axis(ypp, (k - 1)[None], axis=0)[0]
    a_hi = np.take_along_axis(ypp, k[None], axis=0)[0]
    with np.errstate(divide="ignore", invalid="ignore"):
        frac = np.where(a_lo != a_hi, a_lo / (a_lo - a_hi), 0.5)
    s_star = (k - 1 + np.clip(frac, 0.0, 1.0)) * h
    at = np.maximum(s_star[:, :, None] + offsets_v[None, :, :], 0.0)
    column = np.broadcast_to(np.arange(d * (n - 1)).reshape(d, n - 1, 1), at.shape)
    v = hermite(h, yp.reshape(yp.shape[0], -1), ypp.reshape(yp.shape[0], -1), at, column)
    model_v = np.maximum(_parabola_peak(offsets_v, v * sgn[:, :, None]), 0.0)
    return model_y, np.where(moving, model_v, 0.0)


def _restoring_band(
    decay: EnergyDecay, draws: ParameterDraws, sign0: float, tau: NDArray
) -> tuple[NDArray, NDArray]:
    """y and y' of each draw (D, T) at ``tau`` on the decay's nonlinear restoring force:
    from the last turning point before each time (at rest after a stop)."""
    kernel = decay.restoring
    turned, before = first_turn(decay, draws)
    chain = chains(kernel, turned, sign0, float(tau[-1]) + float(np.max(before)), 1_000_000)
    chain = [(tn - b, yn, stopped) for (tn, yn, stopped), b in zip(chain, before, strict=True)]
    d, length = len(chain), max(yn.size for _, yn, _ in chain)
    turns = np.zeros((d, length))
    k = np.empty((d, tau.size), dtype=np.int64)
    since = np.empty((d, tau.size))
    still = np.zeros((d, tau.size), dtype=bool)
    for i, (tn, yn, stopped) in enumerate(chain):
        turns[i, : yn.size] = yn
        k[i] = np.clip(np.searchsorted(tn, tau, side="right") - 1, 0, tn.size - 1)
        since[i] = tau - tn[k[i]]
        still[i] = stopped & (k[i] == tn.size - 1)
    span = float(np.max(np.where(still, 0.0, since)))
    h, y, yp, ypp = rest_grid(
        kernel.spring,
        turns,
        -np.sign(turns),
        draws.zeta[:, None],
        draws.mu[:, None],
        span,
    )
    g = y.shape[0]
    column = np.arange(d)[:, None] * length + k
    y_at = hermite(h, y.reshape(g, -1), yp.reshape(g, -1), since, column)
    yp_at = hermite(h, yp.reshape(g, -1), ypp.reshape(g, -1), since, column)
    start = np.take_along_axis(turns, k, axis=1)
    return np.where(still, start, y_at), np.where(still, 0.0, yp_at)
