"""Windowed fits: ζ and μ_k in windows of a few oscillations moving along the decay.

The paper checks that the friction law holds along the whole decay by moving an
observation window of fixed length along the time axis and finding the same (ζ, μ_k)
in every window (Rigaud et al. 2010, section 3.1, after Wu et al. 2007). Here the
analysed decay (:func:`bayestribo.signal.decay.energy_decay`) is cut at its displacement
turning points into consecutive, non-overlapping windows of ``window`` oscillations
(2·``window`` half cycles); what is left after the last whole window (less than
``window`` oscillations, up to the end of motion) joins the last window, so no
sample is left out. Non-overlapping windows keep the window estimates independent,
which the constancy test (:mod:`bayestribo.adequacy.constancy`) relies on.

Each window is fitted by a *window fitter*, an object with a ``fit_window`` method
(:class:`WindowFitter`). Two are provided:

* :class:`LeastSquaresWindows` (the default): :func:`bayestribo.adequacy.segments.fit_segment`,
  least squares on the window's Π increments with the exact model, i.e. the maximum
  of the likelihood the Bayesian fit samples, with Gaussian intervals from its
  curvature;
* :class:`BayesianWindows`: each window is cut out of the run as a run of its own,
  from a quarter period before its first turning point, and passed to the Bayesian
  fit (:func:`bayestribo.inference.fit` with ``skip_oscillations=0``, or any function
  given to it); the intervals are posterior quantiles.

A user's own fitter (another estimator, another law) is any object with the same
``method``, ``interval_kind``, ``holds_friction`` attributes and ``check`` and
``fit_window`` methods.

Each window reports its amplitude range (the |Y_n| of its turning points) and its
peak-velocity range (the largest |v| of each of its half cycles), in signal units.
"""

from __future__ import annotations

import itertools
import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, ClassVar, Literal, Protocol

import numpy as np
from numpy.typing import NDArray

from bayestribo.adequacy.segments import (
    fit_segment,
    peak_positions,
    segment_noise,
    whole_decay_fit,
)
from bayestribo.errors import BayestriboError, RecordingError
from bayestribo.io.acceleration import motion_edges
from bayestribo.signal.decay import EnergyDecay, energy_decay
from bayestribo.summary import ParameterSummary

__all__ = [
    "BayesianWindows",
    "LeastSquaresWindows",
    "WindowContext",
    "WindowEstimate",
    "WindowFit",
    "WindowFitter",
    "WindowedAnalysis",
    "analysed_decay",
    "friction_symbol",
    "window_bounds",
    "windowed_fits",
]

Friction = Literal["auto", "fit", "fixed"]

#: Two-sided probability of the reported intervals.
INTERVAL_PROB = 0.95
_Z95 = 1.959963984540054


def analysed_decay(run: Any, *, skip_oscillations: int = 1) -> EnergyDecay:
    """The energy decay of a run (a :class:`bayestribo.io.run.Run`, a path, or a decay).

    A run whose ``restoring`` names a nonlinear force (a pendulum, a Duffing spring) is
    analysed on it, as the fit analyses it
    (:func:`bayestribo.adequacy.restoring.restoring_decay`).

    Raises
    ------
    RecordingError
        When the argument is none of those, or the recording cannot be analysed.
    """
    from bayestribo.adequacy.restoring import nonlinear, restoring_decay

    if isinstance(run, EnergyDecay):
        return run
    run = _as_run(run)
    if nonlinear(run):
        return restoring_decay(run, skip_oscillations=skip_oscillations)
    return energy_decay(
        run.time,
        run.displacement,
        run.velocity,
        rig=run.rig(),
        skip_oscillations=skip_oscillations,
        acceleration_edges=motion_edges(dict(run.metadata)),
    )


def _check_window(window: Any) -> int:
    if isinstance(window, bool) or not isinstance(window, int | np.integer) or window < 1:
        raise RecordingError(f"window must be a whole number of oscillations >= 1, got {window!r}")
    return int(window)


def window_bounds(decay: EnergyDecay, window: int) -> list[tuple[int, int, int, int]]:
    """Windows of ``window`` oscillations along a decay.

    Returns
    -------
    list of (start, stop, first_peak, last_peak)
        Sample range ``start:stop`` in the decay's arrays and the range of turning
        points ``first_peak..last_peak`` (inclusive) each window holds. The last
        window runs to the end of the analysed decay.

    Raises
    ------
    RecordingError
        When the decay holds less than one window.
    """
    window = _check_window(window)
    pos = peak_positions(decay)
    half = 2 * window
    n_peaks = pos.size
    count = (n_peaks - 1) // half
    if count < 1:
        raise RecordingError(
            f"the analysed decay holds {(n_peaks - 1) / 2:g} oscillations, fewer than one "
            f"window of {window}; choose a shorter window"
        )
    out = []
    for k in range(count):
        first, last = k * half, (k + 1) * half
        if k == count - 1:
            out.append((int(pos[first]), decay.t.size, first, n_peaks - 1))
        else:
            out.append((int(pos[first]), int(pos[last]) + 1, first, last))
    return out


def friction_symbol(friction_name: str, length_unit: str) -> str:
    """The symbol of a windowed fit's friction: ``μ_k`` (``"mu_k"``), ``θ_c`` (a friction
    displacement in radians: a rotation's friction angle) or ``x_c``."""
    if friction_name == "mu_k":
        return "μ_k"
    if friction_name == "friction_displacement":
        return "θ_c" if length_unit == "rad" else "x_c"
    return friction_name


@dataclass(frozen=True)
class WindowEstimate:
    """ζ and μ in one window, with the window's amplitude and velocity range.

    Attributes
    ----------
    index : int
        Window number along the decay (0 first).
    t_start, t_end : float
        Window limits [s] (recording time).
    n_oscillations : float
        Oscillations in the window (half cycles / 2).
    amplitude : float
        Mean |Y_n| of the turning points that start its half cycles [signal length
        unit]: the amplitude the window's estimates belong to.
    amplitude_range : tuple of float
        Smallest and largest |Y_n| of its turning points [signal length unit].
    velocity_range : tuple of float
        Smallest and largest peak |v| of its half cycles [signal length unit/s].
    zeta, mu : float
        Estimates (posterior medians for the Bayesian fit) of ζ [-] and of the
        friction: μ_k [-] with a loaded rig, else the friction displacement x_c
        [signal length unit].
    zeta_interval, mu_interval : tuple of float
        95 % intervals.
    covariance : ndarray
        2×2 covariance of (ζ, μ) (posterior covariance for the Bayesian fit).
    method : str
        ``"least_squares"`` or ``"bayes"``.
    chi2_reduced : float or None
        Reduced χ² of the window's least-squares fit.
    notes : str
        Bounds reached, convergence.
    """

    index: int
    t_start: float
    t_end: float
    n_oscillations: float
    amplitude: float
    amplitude_range: tuple[float, float]
    velocity_range: tuple[float, float]
    zeta: float
    mu: float
    zeta_interval: tuple[float, float]
    mu_interval: tuple[float, float]
    covariance: NDArray
    method: str
    chi2_reduced: float | None = None
    notes: str = ""
    at_bound: tuple[str, ...] = ()

    @property
    def regular(self) -> bool:
        """False when the estimate sits on a parameter bound (not a Gaussian summary)."""
        return not self.at_bound

    def summary(self, prob: float = 0.95) -> dict[str, ParameterSummary]:
        """Normal summaries (estimate, covariance) of ``zeta`` and ``mu`` in this window."""
        return {
            "zeta": ParameterSummary.from_normal(self.zeta, self.zeta_se, prob),
            "mu": ParameterSummary.from_normal(self.mu, self.mu_se, prob),
        }

    @property
    def zeta_se(self) -> float:
        """Standard deviation of ζ [-]."""
        return math.sqrt(max(float(self.covariance[0, 0]), 0.0))

    @property
    def mu_se(self) -> float:
        """Standard deviation of μ (same unit as ``mu``)."""
        return math.sqrt(max(float(self.covariance[1, 1]), 0.0))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {
            "index": self.index,
            "t_start_s": self.t_start,
            "t_end_s": self.t_end,
            "n_oscillations": self.n_oscillations,
            "amplitude": self.amplitude,
            "amplitude_range": list(self.amplitude_range),
            "velocity_range": list(self.velocity_range),
            "zeta": self.zeta,
            "zeta_se": self.zeta_se,
            "zeta_interval": list(self.zeta_interval),
            "mu": self.mu,
            "mu_se": self.mu_se,
            "mu_interval": list(self.mu_interval),
            "method": self.method,
            "chi2_reduced": self.chi2_reduced,
            "notes": self.notes,
            "at_bound": list(self.at_bound),
        }


@dataclass(frozen=True)
class WindowedAnalysis:
    """Window estimates of one decay.

    Attributes
    ----------
    windows : list of WindowEstimate
    window_oscillations : int
        Window length requested [oscillations].
    method : str
    friction_name : str
        ``"mu_k"`` (dimensionless, loaded rig) or ``"friction_displacement"``
        (signal length unit).
    length_unit : str
        Unit of amplitudes (``"m"``, ``"rad"`` for a rotation's angles, or
        ``"signal unit"``).
    length_scale : float
        ℓ of the decay's scaling [length unit]: μ_k·ℓ is the friction displacement.
    interval_kind : str
        How the intervals were obtained.
    """

    windows: list[WindowEstimate]
    window_oscillations: int
    method: str
    friction_name: str
    length_unit: str
    length_scale: float
    interval_kind: str
    extra: dict[str, Any] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.windows)

    @property
    def friction_symbol(self) -> str:
        """The friction's symbol in prose: μ_k, the friction angle θ_c of a rotation, or
        the friction displacement x_c."""
        return friction_symbol(self.friction_name, self.length_unit)

    def column(self, name: str) -> NDArray:
        """One attribute over the windows as an array (``"zeta"``, ``"amplitude"``...)."""
        return np.array([getattr(w, name) for w in self.windows], dtype=float)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping."""
        return {
            "window_oscillations": self.window_oscillations,
            "method": self.method,
            "friction": self.friction_name,
            "length_unit": self.length_unit,
            "interval": self.interval_kind,
            **self.extra,
            "windows": [w.to_dict() for w in self.windows],
        }


def _velocity_peaks(yp: NDArray, pos: NDArray) -> NDArray:
    """Largest |y'| of each half cycle between successive turning points."""
    out = []
    for a, b in itertools.pairwise(pos):
        seg = np.abs(yp[a : b + 1])
        out.append(float(np.max(seg)) if seg.size else 0.0)
    return np.array(out)


def _window_ranges(
    decay: EnergyDecay, start: int, stop: int, first: int, last: int
) -> tuple[float, tuple[float, float], tuple[float, float]]:
    ell = decay.scaling.length_scale
    omega = decay.scaling.omega
    amps = np.abs(decay.peaks.value[first : last + 1])
    pos = np.append(peak_positions(decay)[first : last + 1], stop - 1)
    pos = np.unique(np.clip(pos, start, stop - 1))
    vel = _velocity_peaks(decay.yp, pos) * ell * omega
    vel = vel[vel > 0.0] if np.any(vel > 0.0) else vel
    mean_amp = float(np.mean(amps[:-1])) if amps.size > 1 else float(amps[0])
    return (
        mean_amp,
        (float(np.min(amps)), float(np.max(amps))),
        (float(np.min(vel)), float(np.max(vel))) if vel.size else (0.0, 0.0),
    )


@dataclass(frozen=True)
class WindowContext:
    """What a window fitter is given about the decay it works on.

    Attributes
    ----------
    decay : EnergyDecay
        The analysed decay.
    run : Run or None
        The recording itself (None when only a decay was given).
    mu_scale : float
        Factor from the dimensionless friction μ_k to the reported one: 1 with a
        loaded rig (μ_k), ℓ [signal length unit] otherwise (a friction displacement).
    seed : int
        Base seed; window ``k`` uses ``seed + k`` or ``seed``.
    """

    decay: EnergyDecay
    run: Any
    mu_scale: float
    seed: int

    @property
    def length_scale(self) -> float:
        """ℓ of the decay's scaling [length unit]."""
        return self.decay.scaling.length_scale


@dataclass(frozen=True)
class WindowFit:
    """ζ and the friction fitted in one window, in the reported units.

    Attributes
    ----------
    zeta, mu : float
        Estimates of ζ [-] and of the friction (μ_k [-] or x_c [signal length unit]).
    covariance : ndarray
        2×2 covariance of (ζ, μ).
    zeta_interval, mu_interval : tuple of float
        95 % intervals.
    chi2_reduced : float or None
        Reduced χ² of a least-squares fit.
    notes : str
        Bounds reached, convergence.
    at_bound : tuple of str
        Parameters whose estimate sits on a bound.
    """

    zeta: float
    mu: float
    covariance: NDArray
    zeta_interval: tuple[float, float]
    mu_interval: tuple[float, float]
    chi2_reduced: float | None = None
    notes: str = ""
    at_bound: tuple[str, ...] = ()


class WindowFitter(Protocol):
    """How one window is fitted (see :class:`LeastSquaresWindows`, :class:`BayesianWindows`).

    Attributes
    ----------
    method : str
        Name in the results (``"least_squares"``, ``"bayes"``...).
    interval_kind : str
        How the intervals are obtained, in words.
    holds_friction : bool
        True when the fitter can hold μ at a given value (the ``friction`` modes of
        :func:`windowed_fits`); False when it always fits it.
    """

    method: str
    interval_kind: str
    holds_friction: bool

    def check(self, context: WindowContext, window: int) -> None:
        """Raise if the fitter cannot work on these windows."""

    def fit_window(
        self,
        context: WindowContext,
        index: int,
        bounds: tuple[int, int, int, int],
        fixed_mu: float | None,
    ) -> WindowFit:
        """Fit window ``index`` with sample range and turning points ``bounds``
        (:func:`window_bounds`), μ held at ``fixed_mu`` (dimensionless) if given."""
        ...


def _gaussian_interval(value: float, sd: float) -> tuple[float, float]:
    return (value - _Z95 * sd, value + _Z95 * sd)


@dataclass(frozen=True)
class LeastSquaresWindows:
    """Least squares on each window's Π increments (Gaussian intervals from the
    curvature, scaled by the reduced χ² when above 1).

    On a velocity-only record (the displacement integrated from the velocity) each
    window also fits its own offset from the equilibrium (the integral's constant
    wanders with the integrated noise, and the windows resolve μ_k to 1e-5 of itself),
    its covariance is the Monte Carlo's of the estimates (the integrated noise's
    increments are correlated), and the model counts the energy at rest after the
    stop up to the last window's end (:func:`~bayestribo.adequacy.segments.fit_segment`).
    Without these the windows of such a record of the law changed μ_k with the
    amplitude by tens of their sd (``tests/test_adequacy_velocity_only.py``).
    """

    method: ClassVar[str] = "least_squares"
    interval_kind: ClassVar[str] = (
        "Gaussian 95 % interval from the least-squares curvature (scaled by the reduced χ² "
        "when above 1)"
    )
    holds_friction: ClassVar[bool] = True

    def check(self, context: WindowContext, window: int) -> None:
        """Any decay of at least one window can be fitted."""

    def fit_window(
        self,
        context: WindowContext,
        index: int,
        bounds: tuple[int, int, int, int],
        fixed_mu: float | None,
    ) -> WindowFit:
        """Least-squares fit of one window (:func:`~bayestribo.adequacy.segments.fit_segment`)."""
        decay, scale = context.decay, context.mu_scale
        start, stop, first, last = bounds
        peaks_abs = np.abs(decay.peaks.value) / context.length_scale
        integrated = decay.derived_channel == "displacement"
        fit = fit_segment(
            decay,
            start,
            stop,
            peaks_abs[first : last + 1],
            noise=segment_noise(decay),
            seed=context.seed + index,
            fixed_mu=fixed_mu,
            free_offset=integrated,
            rest_energy=integrated,
        )
        cov = fit.covariance[:2, :2].copy()
        cov[1, :] *= scale
        cov[:, 1] *= scale
        notes = []
        if fit.at_bound:
            notes.append("at a bound: " + ", ".join(fit.at_bound))
        if fit.notes:
            notes.append(fit.notes)
        se = np.sqrt(np.maximum(np.diag(cov), 0.0))
        mu = fit.mu * scale
        return WindowFit(
            zeta=fit.zeta,
            mu=mu,
            covariance=cov,
            zeta_interval=_gaussian_interval(fit.zeta, float(se[0])),
            mu_interval=_gaussian_interval(mu, float(se[1])),
            chi2_reduced=fit.chi2_reduced,
            notes="; ".join(notes),
            at_bound=fit.at_bound,
        )


def _sub_run(run: Any, t_from: float, t_to: float) -> Any:
    from bayestribo.io.run import Run

    sel = (run.time >= t_from) & (run.time <= t_to)
    return Run(
        time=run.time[sel],
        displacement=None if run.displacement is None else run.displacement[sel],
        velocity=None if run.velocity is None else run.velocity[sel],
        metadata=dict(run.metadata),
        source=run.source,
    )


def _posterior_samples(result: Any, mu_factor: float) -> tuple[NDArray, NDArray]:
    """ζ and friction samples of a window fit, the friction in the windows' unit.

    The friction is taken from ``friction_displacement`` (what the data fix) times
    ``mu_factor`` (1/ℓ for μ_k, 1 for a displacement), so that a calibration
    uncertainty of the load or the mass, common to all windows, does not enter the
    comparison between windows; ``mu_k`` only when no displacement is given.
    """
    zeta = np.asarray(result.samples("zeta"), dtype=float)
    names = list(getattr(result, "parameter_names", ["friction_displacement"]))
    if "friction_displacement" in names:
        mu = np.asarray(result.samples("friction_displacement"), dtype=float) * mu_factor
    else:
        mu = np.asarray(result.samples("mu_k"), dtype=float)
    return zeta, mu


@dataclass(frozen=True)
class BayesianWindows:
    """The Bayesian fit on each window cut out as a run (posterior intervals).

    Parameters
    ----------
    fit : callable, optional
        ``fit(run) -> result`` with ``result.samples(name)`` (and optionally
        ``converged``); default :func:`bayestribo.inference.fit` with the exact model,
        ``skip_oscillations=0`` and the windows' seed.
    """

    fit: Callable[[Any], Any] | None = None
    method: ClassVar[str] = "bayes"
    interval_kind: ClassVar[str] = "posterior 2.5-97.5 % quantiles"
    holds_friction: ClassVar[bool] = False

    def check(self, context: WindowContext, window: int) -> None:
        """A window must be a run of its own: the run itself, at least 3 oscillations.

        Raises
        ------
        RecordingError
            For windows shorter than :data:`bayestribo.signal.decay.MIN_OSCILLATIONS`.
        BayestriboError
            When only an EnergyDecay was given.
        """
        from bayestribo.signal.decay import MIN_OSCILLATIONS

        if window < MIN_OSCILLATIONS:
            raise RecordingError(
                f"window must be at least {MIN_OSCILLATIONS} oscillations with Bayesian "
                f"windows (a run shorter than that cannot be analysed on its own), got {window}"
            )
        if context.run is None:
            raise BayestriboError("Bayesian windows need the run itself, not an EnergyDecay")

    def _fit(self, sub: Any, seed: int) -> Any:
        if self.fit is not None:
            return self.fit(sub)
        from bayestribo.inference import fit

        return fit(sub, model="exact", seed=seed, skip_oscillations=0)

    def fit_window(
        self,
        context: WindowContext,
        index: int,
        bounds: tuple[int, int, int, int],
        fixed_mu: float | None,
    ) -> WindowFit:
        """Bayesian fit of one window cut out as a run (``fixed_mu`` is not used)."""
        decay = context.decay
        start, stop, _, _ = bounds
        period = 2.0 * decay.peaks.half_period
        # The sub-run starts one oscillation early: the fit skips it as the release.
        t_from = float(decay.t[start]) - period - 0.25 * period
        result = self._fit(_sub_run(context.run, t_from, float(decay.t[stop - 1])), context.seed)
        zs, ms = _posterior_samples(result, context.mu_scale / context.length_scale)
        zi = np.quantile(zs, [0.025, 0.975])
        mi = np.quantile(ms, [0.025, 0.975])
        return WindowFit(
            zeta=float(np.median(zs)),
            mu=float(np.median(ms)),
            covariance=np.cov(np.vstack([zs, ms])),
            zeta_interval=(float(zi[0]), float(zi[1])),
            mu_interval=(float(mi[0]), float(mi[1])),
            notes="" if getattr(result, "converged", True) else "sampler not converged",
        )


def _estimate(
    context: WindowContext,
    fitter: WindowFitter,
    index: int,
    bounds: tuple[int, int, int, int],
    fixed_mu: float | None,
) -> WindowEstimate:
    start, stop, first, last = bounds
    decay = context.decay
    amp, amp_range, vel_range = _window_ranges(decay, start, stop, first, last)
    fit = fitter.fit_window(context, index, bounds, fixed_mu)
    return WindowEstimate(
        index=index,
        t_start=float(decay.t[start]),
        t_end=float(decay.t[stop - 1]),
        n_oscillations=(last - first) / 2.0,
        amplitude=amp,
        amplitude_range=amp_range,
        velocity_range=vel_range,
        zeta=float(fit.zeta),
        mu=float(fit.mu),
        zeta_interval=(float(fit.zeta_interval[0]), float(fit.zeta_interval[1])),
        mu_interval=(float(fit.mu_interval[0]), float(fit.mu_interval[1])),
        covariance=np.asarray(fit.covariance, dtype=float),
        method=fitter.method,
        chi2_reduced=fit.chi2_reduced,
        notes=fit.notes,
        at_bound=tuple(fit.at_bound),
    )


def windowed_fits(
    run: Any,
    *,
    window: int = 2,
    fitter: WindowFitter | None = None,
    skip_oscillations: int = 1,
    seed: int = 0,
    friction: Friction = "auto",
    progress: Callable[[str], None] | None = None,
) -> WindowedAnalysis:
    """Fit ζ and μ_k in consecutive windows of ``window`` oscillations along a decay.

    Parameters
    ----------
    run : Run, path or EnergyDecay
        The recording (an EnergyDecay only with a fitter that does not need the run).
    window : int
        Window length [oscillations], default 2.
    fitter : WindowFitter, optional
        How each window is fitted: :class:`LeastSquaresWindows` (default),
        :class:`BayesianWindows`, or a user's own object with the same methods.
    skip_oscillations : int
        Oscillations after the release left out (as :func:`energy_decay`).
    seed : int
        Seed of the whole-decay fit and base seed of the window fits.
    friction : {"auto", "fit", "fixed"}
        For fitters that can hold the friction (``holds_friction``). ``"fit"``: ζ and
        μ in every window. ``"fixed"``: μ held at the whole-decay estimate and ζ
        fitted per window, i.e. the *equivalent* damping of each window (what a
        viscous-like law that changes with amplitude shows). ``"auto"``: ``"fit"``
        when the whole-decay fit resolves the friction (μ above three standard
        errors) and most windows then give estimates inside the parameter bounds,
        else ``"fixed"`` (in a window of a few oscillations ζ and μ cannot be told
        apart when the friction is weak or the noise high).
    progress : callable, optional
        Called with a one-line message before each window is fitted.

    Returns
    -------
    WindowedAnalysis

    Raises
    ------
    RecordingError
        Bad window or friction mode, a decay shorter than one window, or a recording
        that cannot be analysed.
    BayestriboError
        A fitter that cannot work on what was given (e.g. Bayesian windows on an
        EnergyDecay).
    """
    window = _check_window(window)
    if friction not in ("auto", "fit", "fixed"):
        raise RecordingError(f"friction must be 'auto', 'fit' or 'fixed', got {friction!r}")
    fitter = LeastSquaresWindows() if fitter is None else fitter
    recording = None if isinstance(run, EnergyDecay) else _as_run(run)
    decay = analysed_decay(recording or run, skip_oscillations=skip_oscillations)
    bounds = window_bounds(decay, window)
    ell = decay.scaling.length_scale
    loaded = decay.scaling.friction_defined
    context = WindowContext(
        decay=decay,
        run=recording,
        mu_scale=1.0 if loaded else ell,
        seed=seed,
    )
    fitter.check(context, window)
    whole = whole_decay_fit(decay, seed=seed)
    resolved = "mu" not in whole.at_bound and whole.mu > 3.0 * whole.se("mu")
    mode = ("fit" if resolved else "fixed") if friction == "auto" else friction
    if not fitter.holds_friction:
        mode = "fit"
    fixed_mu = whole.mu if mode == "fixed" else None

    def run_windows(fixed_mu: float | None) -> list[WindowEstimate]:
        out = []
        for k, b in enumerate(bounds):
            if progress is not None:
                held = "" if fixed_mu is None else ", friction held"
                progress(f"window {k + 1}/{len(bounds)} ({fitter.method}{held})")
            out.append(_estimate(context, fitter, k, b, fixed_mu))
        return out

    out = run_windows(fixed_mu)
    irregular = sum(not w.regular for w in out)
    if fitter.holds_friction and friction == "auto" and mode == "fit" and 2 * irregular > len(out):
        # ζ and μ cannot be told apart in most windows: equivalent damping instead.
        mode, fixed_mu = "fixed", whole.mu
        out = run_windows(fixed_mu)
    scale = context.mu_scale
    # metres with a load (ℓ = N/k), or where the recording says so (another rig's position
    # in metres); otherwise the signal's own unit
    stated = getattr(recording, "length_unit", None)
    in_metres = loaded or stated == "m"
    return WindowedAnalysis(
        windows=out,
        window_oscillations=window,
        method=fitter.method,
        friction_name="mu_k" if loaded else "friction_displacement",
        length_unit="m" if in_metres else ("rad" if stated == "rad" else "signal unit"),
        length_scale=ell,
        interval_kind=fitter.interval_kind,
        extra={
            "friction_mode": mode,
            "fixed_friction": None if fixed_mu is None else fixed_mu * scale,
            "whole_decay": {
                "zeta": whole.zeta,
                "zeta_se": whole.se("zeta"),
                "mu": whole.mu * scale,
                "mu_se": whole.se("mu") * scale,
                "chi2_reduced": whole.chi2_reduced,
            },
        },
    )


def _as_run(run: Any) -> Any:
    """A Run from a Run or a path (read by :func:`bayestribo.io.as_run`)."""
    from bayestribo.io import as_run
    from bayestribo.io.run import Run

    if not isinstance(run, Run | str | os.PathLike):
        raise RecordingError(
            f"run must be a bayestribo Run, a run file path or an EnergyDecay, got {type(run)}"
        )
    return as_run(run)
