r"""Constancy test: do ζ and μ_k change with amplitude along the decay?

The linear law y'' + 2ζy' + y = -μ_k sgn(y') (Eq. 7) holds with one (ζ, μ_k) for the
whole decay, so the window estimates of :func:`bayestribo.adequacy.windows.windowed_fits`
must agree whatever the window's amplitude. The test fits a straight line in the
window amplitude ``a_w`` to both parameters at once,

.. math::  ζ_w = \bar ζ + b_ζ (a_w - \bar a),\qquad μ_w = \bar μ + b_μ (a_w - \bar a),

by generalised least squares with each window's 2×2 covariance of (ζ_w, μ_w) (in a
window ζ and μ trade off strongly, and ignoring that wastes most of the
information), and tests ``b_ζ = b_μ = 0`` jointly (frequentist, a Wald test: the
window estimates are least-squares or posterior summaries, so this is the stated
frequentist equivalent of a posterior on the trend).

Calibration. Non-overlapping windows have independent noise, so the window
estimates are independent, and each window's covariance is already widened by its
own fit's reduced χ² when that exceeds one. The decision combines two χ² tests on
the trusted covariances: the joint trend (``W ~ χ²_2``) and the scatter of the
windows about the line (``χ² ~ χ²_{2n-4}``, which catches a dependence that is not
linear, e.g. a damping that first falls and then rises with amplitude), with a
Bonferroni factor 2, so the nominal false-alarm rate is ``alpha``. With
``scale_from_scatter=True`` the scatter widens the covariances instead and the
trend alone is tested with the F law. The benchmark ``benchmarks/adequacy.py``
measures the real false-alarm and detection rates on simulated runs.

The report gives each trend as the change of the parameter from the smallest to
the largest window amplitude, absolute and relative to its mean, with a 95 %
interval, and one plain sentence.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.stats
from numpy.typing import NDArray

from bayestribo.adequacy.windows import WindowedAnalysis
from bayestribo.errors import RecordingError
from bayestribo.summary import ParameterSummary

__all__ = ["AmplitudeTrend", "ConstancyTest", "constancy_test"]

#: Fewest windows for the test (two parameters per window, four in the model).
MIN_WINDOWS = 3


@dataclass(frozen=True)
class AmplitudeTrend:
    """Linear trend of one parameter with amplitude across windows.

    Attributes
    ----------
    name : str
        ``"zeta"`` or the friction's name.
    mean : float
        Value at the mean window amplitude.
    slope, slope_se : float
        Change per unit amplitude and its standard error (scaled by s when s > 1).
    change : float
        Change from the smallest to the largest window amplitude, ``slope·Δa``.
    change_interval : tuple of float
        95 % interval of ``change``.
    relative_change : float or None
        ``change / mean`` (None when the mean is not positive).
    span : float
        Δa, the largest minus the smallest window amplitude [signal length unit].
    """

    name: str
    mean: float
    slope: float
    slope_se: float
    change: float
    change_interval: tuple[float, float]
    relative_change: float | None
    span: float

    def summary(self, prob: float = 0.95) -> dict[str, ParameterSummary]:
        """Normal summaries of the trend.

        Parameters
        ----------
        prob : float
            Probability of the normal-approximation intervals, in (0, 1).

        Returns
        -------
        dict of str to ParameterSummary
            ``"slope"`` (per unit amplitude, sd ``slope_se``) and ``"change"`` from the
            smallest to the largest window amplitude (sd ``slope_se·Δa``).
        """
        return {
            "slope": ParameterSummary.from_normal(self.slope, self.slope_se, prob),
            "change": ParameterSummary.from_normal(self.change, self.slope_se * self.span, prob),
        }

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {
            "name": self.name,
            "mean": self.mean,
            "slope": self.slope,
            "slope_se": self.slope_se,
            "change": self.change,
            "change_interval": list(self.change_interval),
            "relative_change": self.relative_change,
        }


@dataclass(frozen=True)
class ConstancyTest:
    """Result of the constancy test.

    Attributes
    ----------
    constant : bool
        True when the data do not show a trend at level ``alpha``.
    p_value : float
        Of the decision (see ``scale_from_scatter`` of :func:`constancy_test`).
    p_trend, p_scatter : float
        Of the joint trend ``b_ζ = b_μ = 0`` and of the scatter about the line.
    alpha : float
        Nominal false-alarm rate.
    zeta, mu : AmplitudeTrend
        The trends.
    scale : float
        s² = χ²/dof of the windows about the line (1 when the covariances were
        trusted as they are).
    chi2, dof : float, int
        Of the line fit.
    amplitude_range : tuple of float
        Smallest and largest window amplitude [signal length unit].
    n_windows, n_left_out : int
        Windows used, and windows left out because their estimate sits on a
        parameter bound (ζ = 0, μ = 0, Y_0 at its limit: no Gaussian summary).
    statement : str
        The plain conclusion.
    """

    constant: bool
    p_value: float
    p_trend: float
    p_scatter: float
    alpha: float
    zeta: AmplitudeTrend
    mu: AmplitudeTrend
    scale: float
    chi2: float
    dof: int
    amplitude_range: tuple[float, float]
    n_windows: int
    n_left_out: int
    statement: str

    def summary(self, prob: float = 0.95) -> dict[str, dict[str, ParameterSummary]]:
        """:meth:`AmplitudeTrend.summary` of both trends, by parameter name.

        Parameters
        ----------
        prob : float
            Probability of the normal-approximation intervals, in (0, 1).

        Returns
        -------
        dict
            ``{self.zeta.name: {"slope": ..., "change": ...}, self.mu.name: {...}}``.
        """
        return {t.name: t.summary(prob) for t in (self.zeta, self.mu)}

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {
            "constant": self.constant,
            "p_value": self.p_value,
            "p_trend": self.p_trend,
            "p_scatter": self.p_scatter,
            "alpha": self.alpha,
            "zeta": self.zeta.to_dict(),
            "mu": self.mu.to_dict(),
            "scale": self.scale,
            "chi2": self.chi2,
            "dof": self.dof,
            "amplitude_range": list(self.amplitude_range),
            "n_windows": self.n_windows,
            "n_left_out": self.n_left_out,
            "statement": self.statement,
        }


def _gls(a: NDArray, theta: NDArray, covs: NDArray) -> tuple[NDArray, NDArray, float]:
    """Line fit of (ζ_w, μ_w) on a_w; returns coefficients, their covariance and χ²."""
    n = a.size
    x = np.zeros((2 * n, 4))
    x[0::2, 0] = 1.0
    x[0::2, 1] = a
    x[1::2, 2] = 1.0
    x[1::2, 3] = a
    obs = theta.reshape(-1)
    weight = np.zeros((2 * n, 2 * n))
    for i, c in enumerate(covs):
        weight[2 * i : 2 * i + 2, 2 * i : 2 * i + 2] = np.linalg.pinv(c)
    info = x.T @ weight @ x
    cov = np.linalg.pinv(info)
    coef = cov @ (x.T @ weight @ obs)
    r = obs - x @ coef
    return coef, cov, float(r @ weight @ r)


def _gls1(a: NDArray, obs: NDArray, var: NDArray) -> tuple[NDArray, NDArray, float]:
    """Weighted line fit of one parameter on a_w; coefficients, covariance, χ²."""
    x = np.column_stack([np.ones_like(a), a])
    w = 1.0 / np.maximum(var, 1e-300)
    info = x.T @ (x * w[:, None])
    cov = np.linalg.pinv(info)
    coef = cov @ (x.T @ (w * obs))
    r = obs - x @ coef
    return coef, cov, float(np.sum(w * r * r))


def _trend(
    name: str, mean: float, slope: float, var: float, span: float, crit: float
) -> AmplitudeTrend:
    se = math.sqrt(max(var, 0.0))
    change = slope * span
    half = crit * se * span
    rel = change / mean if mean > 0.0 else None
    return AmplitudeTrend(
        name, mean, slope, se, change, (change - half, change + half), rel, float(span)
    )


#: Largest |value| of a friction held fixed that is a numerical zero (a whole-decay fit
#: whose friction piles on its bound at 0 returns 1e-29, not a measurement).
_ZERO = 1e-12


def _percent(value: float) -> str:
    """A signed percentage in two significant digits, never in exponent form
    (``+110``, not ``+1.1e+02``).

    Examples
    --------
    >>> _percent(108.2), _percent(5.31), _percent(-0.42)
    ('+108', '+5.3', '-0.42')
    """
    return f"{value:+.0f}" if abs(value) >= 100 else f"{value:+.2g}"


def _held_text(value: float) -> str:
    """A friction held at the whole decay's value: that value, or zero where it is a
    numerical zero."""
    return "0 (within numerical precision)" if abs(value) < _ZERO else f"{value:.3g}"


def _describe(name: str, t: AmplitudeTrend) -> str:
    """A trend with amplitude in words: its change from the smallest to the largest
    window amplitude with its 95 % interval, relative where the mean is positive."""
    if t.relative_change is None:
        lo, hi = t.change_interval
        return f"{name} changes by {t.change:.3g} (95 % interval {lo:.3g} to {hi:.3g})"
    lo, hi = (v / t.mean for v in t.change_interval)
    return (
        f"{name} changes by {_percent(100 * t.relative_change)} % from the smallest to the "
        f"largest window amplitude (95 % interval {_percent(100 * lo)} to {_percent(100 * hi)} %)"
    )


def constancy_test(
    windows: WindowedAnalysis, *, alpha: float = 0.05, scale_from_scatter: bool = False
) -> ConstancyTest:
    """Test whether ζ and μ_k are constant across the windows of a decay.

    Parameters
    ----------
    windows : WindowedAnalysis
        From :func:`bayestribo.adequacy.windows.windowed_fits`.
    alpha : float
        Nominal false-alarm rate of the joint test, in (0, 1).
    scale_from_scatter : bool
        False (default): trust the window covariances (each already widened by its
        own fit's reduced χ² when above 1); the decision combines the trend test
        (χ²_k) and the scatter about the line (χ²_dof, a dependence that is not
        linear) with a Bonferroni factor 2. True: widen the covariances by the
        scatter about the line when it exceeds them and use the F test of the
        trend alone (robust to covariances off by a common factor, blind to a
        non-linear dependence).

    Returns
    -------
    ConstancyTest

    Raises
    ------
    RecordingError
        Fewer than three windows, or ``alpha`` outside (0, 1).
    """
    if not 0.0 < float(alpha) < 1.0:
        raise RecordingError(f"alpha must be in (0, 1), got {alpha!r}")
    used = [w for w in windows.windows if w.regular]
    left_out = len(windows) - len(used)
    n = len(used)
    if n < MIN_WINDOWS:
        raise RecordingError(
            f"the constancy test needs at least {MIN_WINDOWS} windows with estimates inside the "
            f"parameter bounds, got {n} ({left_out} on a bound); use a shorter window"
        )
    amp = np.array([w.amplitude for w in used])
    a_mean = float(np.mean(amp))
    a = amp - a_mean
    theta = np.array([[w.zeta, w.mu] for w in used])
    covs = np.array([w.covariance for w in used])
    fixed = bool(np.all(covs[:, 1, 1] == 0.0))
    if fixed:
        # Friction held fixed in the windows: a line in ζ only.
        coef2, cov2, chi2 = _gls1(a, theta[:, 0], covs[:, 0, 0])
        coef = np.array([coef2[0], coef2[1], float(np.mean(theta[:, 1])), 0.0])
        cov = np.zeros((4, 4))
        cov[:2, :2] = cov2
    else:
        coef, cov, chi2 = _gls(a, theta, covs)
    k = 1 if fixed else 2
    dof = k * n - 2 * k
    s2 = chi2 / dof if dof > 0 else 1.0
    trusted = s2 <= 1.0 or scale_from_scatter is False
    scale = 1.0 if trusted else s2
    b = coef[[1, 3]]
    cb = cov[np.ix_([1, 3], [1, 3])] * scale
    wald = float(b[:k] @ np.linalg.pinv(cb[:k, :k]) @ b[:k])
    if trusted or dof <= 0:
        p_trend = float(scipy.stats.chi2.sf(wald, k))
        crit = float(scipy.stats.norm.ppf(0.975))
        # Scatter about the line beyond the covariances: a dependence that is not linear.
        p_scatter = float(scipy.stats.chi2.sf(chi2, dof)) if dof > 0 else 1.0
        p = min(1.0, 2.0 * min(p_trend, p_scatter))
    else:
        p_trend = float(scipy.stats.f.sf(wald / k, k, dof))
        crit = float(scipy.stats.t.ppf(0.975, dof))
        p_scatter = 1.0
        p = p_trend
    span = float(np.max(amp) - np.min(amp))
    tz = _trend("zeta", float(coef[0]), float(coef[1]), float(cb[0, 0]), span, crit)
    tm = _trend(windows.friction_name, float(coef[2]), float(coef[3]), float(cb[1, 1]), span, crit)
    constant = p >= alpha
    unit = windows.length_unit
    # in prose, the symbol: μ_k (x_c for a friction displacement, θ_c for an angle), not
    # the field name
    symbol = windows.friction_symbol
    head = (
        f"ζ and {symbol} are constant within the data's precision "
        f"(p = {p:.2g} for a trend with amplitude, {n} windows from {np.min(amp):.3g} to "
        f"{np.max(amp):.3g} {unit})"
        if constant
        else f"the damping law is not constant along the decay (p = {p:.2g}, {n} windows from "
        f"{np.min(amp):.3g} to {np.max(amp):.3g} {unit}): the linear law is not adequate"
    )
    if fixed:
        friction = f"{symbol} held at the whole-decay value {_held_text(tm.mean)}"
        head = head.replace(f"ζ and {symbol} are", "the equivalent ζ is")
        head = head.replace(
            "the damping law is not constant", "the equivalent ζ changes with amplitude"
        )
    else:
        friction = _describe(symbol, tm)
    statement = f"{head}; {_describe('ζ', tz)}; {friction}."
    if left_out:
        statement += (
            f" {left_out} window(s) with an estimate on a parameter bound (no Gaussian summary) "
            "are shown but not used in the test."
        )
    return ConstancyTest(
        constant=constant,
        p_value=p,
        p_trend=p_trend,
        p_scatter=p_scatter,
        alpha=float(alpha),
        zeta=tz,
        mu=tm,
        scale=float(scale),
        chi2=chi2,
        dof=dof,
        amplitude_range=(float(np.min(amp)), float(np.max(amp))),
        n_windows=n,
        n_left_out=left_out,
        statement=statement,
    )
