"""The single-run pipeline in four public steps.

1. :func:`prepare`: a run becomes observed Π increments: the energy decay
   (:func:`bayestribo.signal.energy_decay`), the noise model
   (:func:`bayestribo.signal.noise_model`) and the increments with their variances
   (:func:`bayestribo.signal.pi_data`);
2. :func:`build_posterior`: default priors (or the caller's) × the Π likelihood, with
   any parameters fixed at a value (``fixed={"zeta": 0.0}`` is the Coulomb-only law);
3. :func:`sample`: maximum a posteriori, the increments' variances again from the
   law's motion there and the optimum of that posterior (the second pass,
   :mod:`bayestribo.inference.reweight`), starting walkers, and the sampler
   (:func:`bayestribo.inference.sampling.run_ensembles`) run to convergence;
4. :func:`summarise`: derived quantities, the misfit check, diagnostics and the
   :class:`~bayestribo.inference.result.FitResult`.

:func:`bayestribo.fit` is these four steps in a row. The dissipation-law comparison
and the Bayesian windows of the adequacy check are built on them too.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import warnings
import zlib
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import scipy.stats
from numpy.typing import NDArray

from bayestribo import __version__
from bayestribo.errors import (
    BayestriboError,
    ConvergenceWarning,
    FrequencyTrendWarning,
    MisfitWarning,
    PriorBoundWarning,
)
from bayestribo.inference.assemble import derived_quantities, fit_draws
from bayestribo.inference.calibration import calibrate_channels
from bayestribo.inference.dissipation import (
    dissipation_amplitudes,
    dissipation_band,
    law_quantities,
    physical_scale,
    shape_agreement,
    turning_point_dissipation,
)
from bayestribo.inference.likelihood import MODELS, PiLikelihood, ShapeDeparture
from bayestribo.inference.modes import mode_check, run_or_failure
from bayestribo.inference.posterior import Posterior
from bayestribo.inference.priors import Prior, PriorSet, default_priors, piled_on_bounds
from bayestribo.inference.result import FitResult, plain_data
from bayestribo.inference.reweight import reweighted_posterior
from bayestribo.inference.sampling import SamplerRun, SamplerSettings, run_ensembles
from bayestribo.inference.sensitivity import prior_sensitivity
from bayestribo.inference.start import initial_walkers, maximum_a_posteriori, maximum_from, refine
from bayestribo.inference.surrogate import (
    ATTEMPTS,
    NODE_SCALE,
    SurrogateCheck,
    check,
    surrogate_posterior,
)
from bayestribo.io.files import as_run
from bayestribo.io.options import ReadOptions
from bayestribo.io.run import Run
from bayestribo.model.laws import Law, get_law
from bayestribo.model.restoring import get_restoring
from bayestribo.signal.decay import EnergyDecay, energy_decay
from bayestribo.signal.frequency import FrequencyTrend, frequency_trend, turning_point_trend
from bayestribo.signal.increments import PiData, pi_data
from bayestribo.signal.noise import NoiseModel, noise_model
from bayestribo.signal.sensor import sensor_calibration

__all__ = [
    "PreparedRun",
    "Sampled",
    "build_posterior",
    "find_optimum",
    "law_frequency",
    "prepare",
    "reframe",
    "sample",
    "summarise",
]

#: Sampler settings of a default fit.
DEFAULT_SETTINGS = SamplerSettings(n_walkers=16, n_ensembles=2, max_steps=20_000)
#: χ² p-value of the MAP residuals below which a fit warns of misfit.
MISFIT_P = 1e-3


@dataclass(frozen=True)
class PreparedRun:
    """A run ready for inference: what the likelihood observes, and where it came from.

    Attributes
    ----------
    run : Run
        The recording.
    name : str
        Its name in messages and results (file or ``run_id``).
    decay : EnergyDecay
        The analysed window and its energy decay.
    noise : NoiseModel
        Nominal resolution against the noise measured at rest.
    data : PiData
        Π increments and their noise variances.
    grid_points, skip_oscillations : int or None
        The preparation settings, recorded in the result.
    channels : dict or None
        The channel calibration (:func:`bayestribo.inference.calibration.calibrate_channels`),
        None for a run with one signal.
    noise_given : bool
        True when the noise model was given rather than measured in the recording.
    """

    run: Run
    name: str
    decay: EnergyDecay
    noise: NoiseModel
    data: PiData
    grid_points: int | None = None
    skip_oscillations: int = 1
    channels: dict[str, Any] | None = None
    noise_given: bool = False

    @property
    def metadata(self) -> dict[str, Any]:
        """The run's metadata."""
        return dict(self.run.metadata)

    @property
    def contact(self) -> bool:
        """False for a test without contact (``load_N`` of 0): no friction to fit."""
        return self.run.metadata.get("load_N") != 0


@dataclass(frozen=True)
class Sampled:
    """The sampled posterior.

    Attributes
    ----------
    posterior : Posterior
    theta_map : ndarray
        Maximum a posteriori in sampling coordinates.
    run : SamplerRun
        Chains and convergence diagnostics.
    settings : SamplerSettings
    surrogate : SurrogateCheck or None
        For a law without a closed form, the check of the quadratic surrogate of Π
        (:mod:`bayestribo.inference.surrogate`): passed when the chains are the
        surrogate posterior's, failed when they are the exact posterior's after it;
        None when no surrogate was tried.
    surrogate_posterior : Posterior or None
        The surrogate posterior the chains sampled (None: the exact one).
    """

    posterior: Posterior
    theta_map: NDArray
    run: SamplerRun
    settings: SamplerSettings
    surrogate: SurrogateCheck | None = None
    surrogate_posterior: Posterior | None = None

    @property
    def draws_posterior(self) -> Posterior:
        """The posterior whose density the chains sampled: the surrogate's where its
        check passed (it then stands for the exact one within
        :data:`~bayestribo.inference.surrogate.MAX_WEIGHT_CV`), else the exact."""
        return self.surrogate_posterior if self.surrogate_posterior is not None else self.posterior


def _run_name(run: Run) -> str:
    return str(run.source or dict(run.metadata).get("run_id", "") or "")


def _data_seed(decay: EnergyDecay) -> int:
    """A seed that is a function of the analysed signals alone (CRC-32 of their bytes)."""
    crc = zlib.crc32(np.ascontiguousarray(decay.y).tobytes())
    return zlib.crc32(np.ascontiguousarray(decay.yp).tobytes(), crc)


def prepare(
    run: Run | str | os.PathLike[str],
    *,
    skip_oscillations: int = 1,
    grid_points: int | None = None,
    noise: NoiseModel | None = None,
    seed: int | np.random.Generator | None = None,
    read_options: ReadOptions | Mapping[str, Any] | None = None,
    correct_channels: bool = True,
    notch: float | Literal["auto"] | None = None,
) -> PreparedRun:
    """Step 1: a run becomes observed Π increments with their noise variances.

    Parameters
    ----------
    run : Run or path
        The recording, or a file read by :func:`bayestribo.io.as_run`.
    skip_oscillations : int
        Oscillations skipped after the release.
    grid_points : int, optional
        Number of Π increments; default one per half cycle.
    noise : NoiseModel, optional
        Use this noise model instead of the recording's.
    seed : int or Generator, optional
        Seed of the Monte Carlo propagation of the noise into the increments of a
        derived channel. Default: a seed computed from the recording itself, so that
        the observation, and every answer drawn from it, is a function of the data and
        not of the fit's seed (the increments' variances carry the Monte Carlo's
        relative error of about 8 %; where the law misfits a record, a fit seeded
        anew with each draw moved by more than one posterior sd).
    read_options : ReadOptions or mapping, optional
        How to read ``run`` when it is a path (:class:`~bayestribo.io.options.ReadOptions`,
        or a mapping of the options of :func:`bayestribo.read_run`).
    correct_channels : bool
        Correct the velocity to the displacement when their gain ratio or delay is
        off (:func:`bayestribo.inference.calibration.calibrate_channels`; a
        :class:`~bayestribo.errors.ChannelCalibrationWarning` either way).
    notch : float, "auto" or None
        Subtract the mains line measured at rest at this frequency [Hz], or the one
        found in the rest spectrum (``"auto"``), from both channels before the
        analysis (:func:`bayestribo.signal.decay.energy_decay`); the result records
        the line removed.

    Returns
    -------
    PreparedRun
    """
    recording, channels = calibrate_channels(as_run(run, read_options), correct=correct_channels)
    decay = energy_decay(
        recording.time,
        recording.displacement,
        recording.velocity,
        rig=recording.rig(),
        skip_oscillations=skip_oscillations,
        notch=notch,
    )
    noise_used = noise or noise_model(decay, dict(recording.metadata))
    if seed is None:
        mc_seed = _data_seed(decay)
    else:
        mc_seed = int(np.random.default_rng(seed).integers(2**31))
    data = pi_data(decay, noise_used, grid_points=grid_points, seed=mc_seed)
    return PreparedRun(
        recording,
        _run_name(recording),
        decay,
        noise_used,
        data,
        grid_points,
        skip_oscillations,
        channels,
        noise is not None,
    )


def reframe(prepared: PreparedRun, frequency_Hz: float) -> PreparedRun:
    """The same run prepared again with time scaled by another natural frequency.

    Parameters
    ----------
    prepared : PreparedRun
        From :func:`prepare`.
    frequency_Hz : float
        The natural frequency [Hz] that scales time (τ = 2πf t), e.g.
        :func:`law_frequency`.

    Returns
    -------
    PreparedRun
        The same window, notch and settings; the noise model measured anew (its
        dimensionless levels follow the frequency) unless it was given.
    """
    run = prepared.run
    old = prepared.decay
    decay = energy_decay(
        run.time,
        run.displacement,
        run.velocity,
        rig=run.rig(),
        skip_oscillations=prepared.skip_oscillations,
        notch=old.notch_Hz[0] if old.notch_Hz else None,
        frequency_Hz=frequency_Hz,
    )
    noise_used = prepared.noise if prepared.noise_given else noise_model(decay, dict(run.metadata))
    data = pi_data(decay, noise_used, grid_points=prepared.grid_points, seed=_data_seed(decay))
    return dataclasses.replace(prepared, decay=decay, noise=noise_used, data=data)


def regrid(prepared: PreparedRun, grid_points: int) -> PreparedRun:
    """The same run observed on another grid of Π increments.

    Parameters
    ----------
    prepared : PreparedRun
        From :func:`prepare`.
    grid_points : int
        Number of Π increments (:func:`bayestribo.signal.increments.pi_data`).

    Returns
    -------
    PreparedRun
        The same decay and noise model, with the increments on the new grid.
    """
    if isinstance(grid_points, bool) or not isinstance(grid_points, (int, np.integer)):
        raise BayestriboError(f"grid_points: expected an integer, got {grid_points!r}")
    if grid_points < 2:
        raise BayestriboError(f"grid_points: expected at least 2, got {grid_points}")
    decay = prepared.decay
    data = pi_data(decay, prepared.noise, grid_points=int(grid_points), seed=_data_seed(decay))
    return dataclasses.replace(prepared, data=data, grid_points=int(grid_points))


def prepare_part(prepared: PreparedRun, start: int, stop: int) -> PreparedRun:
    """Samples ``start`` to ``stop`` (excluded) of a prepared run, prepared alike.

    The part of the recording (already checked, and its channels calibrated, by
    :func:`prepare`) gets the same notch, oscillations skipped, grid and noise model
    (given: measured on the whole, where the rest is); its channels are not checked
    again, since a part that decays into the noise correlates less than the whole.

    Parameters
    ----------
    prepared : PreparedRun
        From :func:`prepare`.
    start, stop : int
        First and past-the-last sample of the part.

    Returns
    -------
    PreparedRun
    """
    run = prepared.run
    if not 0 <= start < stop <= run.time.size:
        raise BayestriboError(
            f"start, stop: expected 0 <= start < stop <= {run.time.size}, got {start}, {stop}"
        )
    keep = slice(start, stop)
    part = dataclasses.replace(
        run,
        time=run.time[keep],
        displacement=None if run.displacement is None else run.displacement[keep],
        velocity=None if run.velocity is None else run.velocity[keep],
    )
    old = prepared.decay
    decay = energy_decay(
        part.time,
        part.displacement,
        part.velocity,
        rig=part.rig(),
        skip_oscillations=prepared.skip_oscillations,
        notch=old.notch_Hz[0] if old.notch_Hz else None,
    )
    data = pi_data(decay, prepared.noise, grid_points=prepared.grid_points, seed=_data_seed(decay))
    return dataclasses.replace(prepared, run=part, decay=decay, data=data, noise_given=True)


def _matched_law_times(
    posterior: Posterior, theta: NDArray, decay: EnergyDecay
) -> tuple[NDArray, NDArray, NDArray] | None:
    """The record's turning times τ (in its frame), the law's at θ matched to them, and
    which of the record's have a match (a turning point of the law within a quarter
    period; the one the record starts just after has none when the law starts in
    motion); None when fewer than 90 % (and 4) have one, or two share one."""
    times = decay.turning_times
    if times is None or np.size(times) < 4:
        return None
    data = posterior.likelihood.data
    params = posterior.physical(np.asarray(theta, dtype=float)[None])["params"]
    values = {k: float(v[0]) for k, v in params.items() if k != "y0"}
    tau_law, _ = posterior.law.turning_points(
        values,
        float(params["y0"][0]),
        float(data.yp0),
        tau_max=float(data.tau_end) + 2.0 * math.pi,
        reference=posterior.likelihood.reference_amplitude,
    )
    if tau_law.size < 3:
        return None
    tau_meas = decay.scaling.omega * (np.asarray(times, dtype=float) - decay.start_time)
    at = np.clip(np.searchsorted(tau_law, tau_meas), 1, tau_law.size - 1)
    nearer = np.where(
        np.abs(tau_law[at - 1] - tau_meas) <= np.abs(tau_law[at] - tau_meas), at - 1, at
    )
    close = np.abs(tau_law[nearer] - tau_meas) <= 0.25 * math.pi
    nearer = nearer[close]
    if close.sum() < max(4, 0.9 * close.size) or np.unique(nearer).size != nearer.size:
        return None
    return tau_meas[close], tau_law[nearer], close


def law_frequency(posterior: Posterior, theta: NDArray, decay: EnergyDecay) -> float | None:
    """The natural frequency [Hz] at which the law's turning times at θ keep step with
    the record's.

    The record's frequency (:func:`bayestribo.signal.decay.energy_decay`) is its damped
    frequency corrected by the decrement's ζ, f_d√(1+β²): exact for viscous damping
    and Coulomb friction, but a nonlinear drag's equivalent damping changes along the
    decay, and the correction is then off by about the spread of β² (quadratic drag of
    ζ_e = 0.02 at the release: 1e-4, two posterior standard deviations of ΔE(A) at ten
    times the vibrometer's resolution). The law's own turning times include what its
    drag does to the period: the slope of the record's turning times against them
    (weighted by |Y_n|, the inverse of their noise) gives the frequency.

    Returns
    -------
    float or None
        None when the turning points cannot be matched.
    """
    pair = _matched_law_times(posterior, theta, decay)
    if pair is None:
        return None
    tau_meas, matched, close = pair
    w = np.abs(np.asarray(decay.peaks.value, dtype=float))[close]
    if w.size != matched.size or not np.all(np.isfinite(w)) or not np.any(w > 0):
        w = np.ones(matched.size)
    slope = float(np.polyfit(matched, tau_meas, 1, w=np.sqrt(w))[0])
    if not (math.isfinite(slope) and slope > 0):
        return None
    return decay.scaling.omega / slope / (2.0 * math.pi)


def build_posterior(
    data: PiData,
    *,
    model: str = "exact",
    friction: bool = True,
    discrepancy: bool = False,
    priors: Mapping[str, Prior] | None = None,
    fixed: Mapping[str, float] | None = None,
    law: str | Law | None = None,
) -> Posterior:
    """Step 2: the posterior for observed Π increments.

    The equilibrium nuisance gets prior standard deviations of 1 % of the initial
    amplitude (δ₀) and 1 % of it over the analysed window (δ₁), hundreds of times
    the errors of the equilibrium estimate.

    Parameters
    ----------
    data : PiData
        Observed increments (:func:`bayestribo.signal.pi_data`).
    model : {"exact", "averaged"}
        Forward model.
    friction : bool
        Fit μ_k and μ_s/μ_k (False: viscous damping only).
    discrepancy : bool
        Add the model-discrepancy terms: white (``log10_discrepancy``) and shape
        (``log10_shape``).
    priors : mapping, optional
        Replacement priors by parameter name (see
        :func:`bayestribo.inference.priors.default_priors`).
    fixed : mapping, optional
        Parameters held at a value instead of sampled, e.g. ``{"zeta": 0.0}`` for
        friction alone; their priors are dropped.
    law : str or Law, optional
        The dissipation law (:mod:`bayestribo.model.laws`): a name such as
        ``"viscous+quadratic+coulomb"``, or a :class:`~bayestribo.model.laws.Law`
        (one of terms defined outside the package too); default
        ``"viscous+coulomb"``.

    Returns
    -------
    Posterior

    Raises
    ------
    BayestriboError
        If a parameter is both given a prior and fixed, a fixed name is unknown, the
        law is unknown, or a prior names a parameter the law does not have.
    """
    if model not in MODELS:
        raise BayestriboError(f"model: expected one of {MODELS}, got {model!r}")
    try:
        the_law = get_law(law)
    except ValueError as exc:
        raise BayestriboError(str(exc)) from None
    if model == "averaged" and not the_law.closed_form:
        raise BayestriboError(
            f"model='averaged' has no closed form for the law {the_law.name}: use model='exact'"
        )
    fixed = dict(fixed or {})
    both = sorted(set(fixed) & set(priors or {}))
    if both:
        raise BayestriboError(f"priors and fixed both name {both}: give one or the other")
    prior_set = default_priors(data.y0, friction=friction, discrepancy=discrepancy, law=the_law)
    if priors:
        try:
            prior_set = prior_set.replace(**dict(priors))
        except ValueError as exc:
            raise BayestriboError(f"priors: {exc} (law {the_law.name})") from None
    if fixed:
        prior_set = PriorSet({n: p for n, p in prior_set.priors.items() if n not in fixed})
    likelihood = PiLikelihood(
        data,
        model=model,  # type: ignore[arg-type]
        offset_sd=max(1e-2 * abs(data.y0), 1e-12),
        drift_sd=max(1e-2 * abs(data.y0) / data.tau_end, 1e-15),
        law=the_law,
    )
    return Posterior(prior_set, likelihood, fixed)


def find_optimum(
    posterior: Posterior,
    decay: EnergyDecay,
    also_start_at: Mapping[str, float] | None = None,
) -> tuple[NDArray, NDArray, tuple[float, float] | None]:
    """The maximum a posteriori of step 3, its Laplace covariance and the plausible
    μ_s/μ_k interval (:func:`bayestribo.inference.start.maximum_a_posteriori`), with a
    second starting point of the optimiser kept if its optimum is better.

    Parameters
    ----------
    posterior : Posterior
        From :func:`build_posterior`.
    decay : EnergyDecay
        The run's energy decay (its peaks give the first guesses of the optimiser).
    also_start_at : mapping, optional
        Values of the sampled coordinates to start the optimiser from as well (e.g.
        the optimum of a nested law).

    Returns
    -------
    theta : ndarray
        The optimum in sampling coordinates.
    cov : ndarray
        Its Laplace covariance.
    ratio_range : tuple or None
        The plausible μ_s/μ_k interval (None for a law without static friction).
    """
    return _better_optimum(posterior, maximum_a_posteriori(posterior, decay), also_start_at)


def _better_optimum(
    posterior: Posterior,
    optimum: tuple[NDArray, NDArray, tuple[float, float] | None],
    also_start_at: Mapping[str, float] | None,
) -> tuple[NDArray, NDArray, tuple[float, float] | None]:
    """``optimum``, or the optimum refined from ``also_start_at`` when its posterior
    density is higher (the μ_s/μ_k interval kept)."""
    theta, cov, ratio_range = optimum
    if also_start_at is not None:
        start = np.array([also_start_at[n] for n in posterior.names], dtype=float)
        if np.isfinite(posterior(start[None])[0]):
            alt, alt_cov = refine(posterior, start)
            if posterior(alt[None])[0] > posterior(theta[None])[0]:
                theta, cov = alt, alt_cov
    return theta, cov, ratio_range


def sample(
    posterior: Posterior,
    decay: EnergyDecay,
    *,
    settings: SamplerSettings = DEFAULT_SETTINGS,
    seed: int | np.random.Generator | None = None,
    also_start_at: Mapping[str, float] | None = None,
    progress: bool = False,
    optimum: tuple[NDArray, NDArray, tuple[float, float] | None] | None = None,
    surrogate: bool = True,
    reweight: bool = True,
) -> Sampled:
    """Step 3: maximum a posteriori, starting walkers, and sampling to convergence.

    Parameters
    ----------
    posterior : Posterior
        From :func:`build_posterior`.
    decay : EnergyDecay
        The run's energy decay (its peaks give the first guesses of the optimiser).
    settings : SamplerSettings
        Walkers, ensembles, step ceiling and stopping rule.
    seed : int or Generator, optional
        Seed of the walkers and of the sampler's moves.
    also_start_at : mapping, optional
        A second starting point of the optimiser (values of the sampled coordinates,
        e.g. the optimum of a nested law), kept if its optimum is better.
    progress : bool
        Show a progress bar.
    optimum : tuple, optional
        The maximum a posteriori, its Laplace covariance and the plausible μ_s/μ_k
        interval when they are known already (:func:`bayestribo.inference.start.
        maximum_from`, a nonlinear law's fit in the frame of its own turning times):
        the optimiser does not run from the first guesses again.
    surrogate : bool
        For a law without a closed form, sample a quadratic surrogate of its Π and keep
        it where the exact posterior confirms it (:mod:`bayestribo.inference.surrogate`;
        the default); False: sample the exact posterior throughout.
    reweight : bool
        The second pass (the default): the increments' variances computed again from
        the law's motion at the optimum, and the optimum of that posterior, which is
        sampled (:mod:`bayestribo.inference.reweight`; the observed channels' variances
        are too large below the noise, and share its sign). False: sample
        ``posterior`` as it is.

    Returns
    -------
    Sampled
        Its ``posterior`` is the one sampled (the second pass's).
    """
    rng = np.random.default_rng(seed)
    if optimum is None:
        optimum = find_optimum(posterior, decay)
    theta, cov, ratio_range = _better_optimum(posterior, optimum, also_start_at)
    if reweight:
        second = reweighted_posterior(posterior, decay, theta)
        if second is not None:
            posterior = second
            theta, cov, ratio_range = maximum_from(posterior, theta, decay)
    checked: SurrogateCheck | None = None
    target: Posterior | None = None
    run: SamplerRun | None = None
    first = None
    if surrogate and not posterior.law.closed_form and posterior.likelihood.model == "exact":
        first = _first_surrogate(posterior, theta, cov)
    # the walkers are kept by the surrogate's density where there is one (it stands for
    # the exact one near the optimum, where they start, at no integration of the law)
    walkers = initial_walkers(
        posterior if first is None else first,
        theta,
        cov,
        ratio_range,
        settings.n_ensembles,
        settings.n_walkers,
        rng,
    )
    seed_of_run = int(rng.integers(2**31))
    if first is not None:
        run, checked, target = _sample_surrogate(
            posterior, theta, cov, walkers, settings, seed_of_run, progress, first
        )
        if run is None:
            # the exact posterior is sampled: its walkers by its own density
            walkers = initial_walkers(
                posterior, theta, cov, ratio_range, settings.n_ensembles, settings.n_walkers, rng
            )
    if run is None:
        # -- a failure inside sampling is a reported non-convergence (inference/modes.py) --
        run = run_or_failure(
            run_ensembles, posterior, walkers, settings, seed=seed_of_run, progress=progress
        )
        # -- end of the failure guard --
    # The optimiser can stop short of the optimum on the ridge of a law that misfits
    # (HarmOsc3 under viscous+coulomb+quadratic: χ² 228590 at its optimum, 8332 where
    # the walkers went); the best point the walkers visited then stands for the MAP
    # in the misfit checks.
    if run.log_prob.size and np.isfinite(run.log_prob).any():
        best = np.unravel_index(np.nanargmax(run.log_prob), run.log_prob.shape)
        point = np.array(run.chains[best], dtype=float)
        if posterior(point[None])[0] > posterior(theta[None])[0]:
            theta = point
    return Sampled(posterior, theta, run, settings, checked, target)


def _first_surrogate(posterior: Posterior, theta: NDArray, cov: NDArray) -> Posterior | None:
    """The surrogate posterior about the maximum a posteriori with the Laplace scales
    (:func:`~bayestribo.inference.surrogate.surrogate_posterior`), or None when it
    cannot be built or has no compiled density (the exact posterior is sampled)."""
    sd = np.sqrt(np.clip(np.diag(np.atleast_2d(cov)), 0.0, None))
    target = surrogate_posterior(posterior, theta, NODE_SCALE * sd)
    if target is None or not target.uses_compiled:
        return None
    if not np.isfinite(target(np.asarray(theta, dtype=float)[None])[0]):
        return None
    return target


def _sample_surrogate(
    posterior: Posterior,
    theta: NDArray,
    cov: NDArray,
    walkers: NDArray,
    settings: SamplerSettings,
    seed: int,
    progress: bool,
    first: Posterior | None = None,
) -> tuple[SamplerRun | None, SurrogateCheck | None, Posterior | None]:
    """Sample the quadratic surrogate posterior of a law without a closed form and
    check it against the exact one (:mod:`bayestribo.inference.surrogate`).

    The surrogate is built about the maximum a posteriori with the Laplace scales
    (``first``, when the caller has built it already); if its check fails, again about
    the best draw checked with the surrogate posterior's spread (up to
    :data:`~bayestribo.inference.surrogate.ATTEMPTS` surrogates). Returns the run, the
    last check and the surrogate posterior when a check passed; ``(None, check, None)``
    when none did (the caller samples the exact posterior).
    """
    rng = np.random.default_rng(seed)
    sd = np.sqrt(np.clip(np.diag(np.atleast_2d(cov)), 0.0, None))
    centre, scale = theta, NODE_SCALE * sd
    checked: SurrogateCheck | None = None
    for attempt in range(1, ATTEMPTS + 1):
        target = first if attempt == 1 and first is not None else None
        if target is None:
            target = surrogate_posterior(posterior, centre, scale)
        if target is None or not target.uses_compiled:
            return None, checked, None
        run = run_or_failure(run_ensembles, target, walkers, settings, seed=seed, progress=progress)
        flat = run.chains.reshape(-1, run.chains.shape[-1])
        if flat.shape[0] < 2 or not np.all(np.isfinite(flat)):
            return None, checked, None
        # a run that did not converge is checked too, and kept when the check passes:
        # the fit reports its non-convergence as an exact run would, at a fraction of
        # the cost of sampling the exact posterior to the step ceiling
        checked = check(posterior, target, flat, rng, attempt=attempt)
        if checked.passed:
            return run, checked, target
        if checked.best is None:
            break
        centre, scale = checked.best, NODE_SCALE * flat.std(axis=0)
    return None, checked, None


def misfit_p_value(chi2: float, m: int, noise_dof: float | None) -> float:
    """p-value of a residual χ² for m increments, with the noise variance's own error.

    The residuals are standardised by a noise variance measured at rest from a finite
    number of samples: the estimate is σ² χ²_ν/ν, ν its degrees of freedom, and
    ``(χ²/m)`` then follows an F(m, ν) distribution, not χ²_m/m. With 200 samples of
    rest (±10 % on σ²) and m = 2000 increments, χ² = 2300 is p = 3e-6 as a χ² but
    p = 0.10 as an F: the rest, not the law, is uncertain by that much.

    Parameters
    ----------
    chi2 : float
        Sum of the squared standardised residuals.
    m : int
        Number of increments.
    noise_dof : float or None
        ν (:attr:`bayestribo.signal.noise.NoiseModel.measured_dof`); None for a noise
        taken as exact (the instrument's resolution): the χ² test.

    Returns
    -------
    float
    """
    if noise_dof is None or not math.isfinite(noise_dof) or noise_dof <= 0:
        return float(scipy.stats.chi2.sf(chi2, m))
    return float(scipy.stats.f.sf(chi2 / m, m, noise_dof))


def _misfit(posterior: Posterior, theta: NDArray) -> tuple[float, int, float]:
    """χ², number of increments and p-value of the standardized residuals at θ
    (:func:`misfit_p_value`, with the degrees of freedom of the measured noise)."""
    resid = posterior.standardized_residuals(theta[None])[0]
    chi2 = float(np.sum(resid * resid))
    preparation = posterior.likelihood.data.preparation or {}
    noise = preparation.get("noise")
    dof = getattr(noise, "measured_dof", None)
    return chi2, int(resid.size), misfit_p_value(chi2, int(resid.size), dof)


def _shape_departure(posterior: Posterior, theta: NDArray) -> ShapeDeparture:
    """The smooth departure of the decay from the law at θ (noise variances alone)."""
    params = posterior.physical(theta[None])["params"]
    return posterior.likelihood.shape_departure({k: float(v[0]) for k, v in params.items()})


#: A half period changing along the decay by more than this fraction, and by more than
#: FREQUENCY_TREND_Z standard errors, is reported: the linear law's Ω is constant.
FREQUENCY_TREND_CHANGE = 2e-4
FREQUENCY_TREND_Z = 4.0


def frequency_nuisance_sd(trend: FrequencyTrend | None) -> float:
    """Relative standard deviation of the frequency nuisance ε from the frequency trend.

    The equivalent constant frequency of a decay whose half period changes by a
    fraction Δ (± its standard error σ_Δ) from the largest swing to the smallest lies
    anywhere in that span: ε gets the standard deviation ½√(Δ² + σ_Δ²), so that its
    95 % interval reaches both ends of the span about the measured frequency (which
    lies inside it). A linear oscillator's Δ is noise, of order σ_Δ, and ε is then
    small beside ζ's own uncertainty (see
    :func:`bayestribo.inference.assemble.derived_quantities`).

    Parameters
    ----------
    trend : FrequencyTrend or None
        From :func:`bayestribo.signal.frequency.frequency_trend` (None: too few half cycles
        to measure a trend, and no nuisance).

    Returns
    -------
    float
    """
    if trend is None or not math.isfinite(trend.change):
        return 0.0
    se = abs(trend.change / trend.z) if trend.z and math.isfinite(trend.z) else 0.0
    return 0.5 * math.hypot(trend.change, se)


def _beyond_the_law(
    posterior: Posterior, theta: NDArray, trend: FrequencyTrend | None, decay: EnergyDecay
) -> tuple[FrequencyTrend | None, float]:
    """The measured frequency trend less the one the law itself makes.

    Viscous damping and Coulomb friction leave the half period constant (Eq. 15);
    a nonlinear drag does not: its equivalent damping, and with it the damped half
    period, changes with amplitude (quadratic drag of ζ_e = 0.02 at the release: the
    half period shortens by 3e-4 over the decay). The law's turning times at the MAP
    (the compiled integrator) are matched to the record's; their departure from
    even spacing is taken off the record's turning times before the trend is fitted
    (:func:`~bayestribo.signal.frequency.turning_point_trend`), so that only a trend the
    law does not make (a stiffness that depends on amplitude) is reported and put into
    the frequency nuisance. (Fitting the law's own turning points with the trend model
    and subtracting the two trends does not work: the model's 1/|Y_n| terms, meant for
    a filter's delay, absorb a drag's trend on exact turning points and not on
    measured ones; the quadratic drag above then left -2.6e-4 at 75 standard errors.)

    Returns
    -------
    trend : FrequencyTrend or None
        The part of the trend beyond the law.
    law_change : float
        The law's own relative change of the half period from the largest swing to the
        smallest (0 for the closed-form laws).
    """
    law = posterior.law
    times = decay.turning_times
    if trend is None or law.closed_form or times is None or not math.isfinite(trend.change):
        return trend, 0.0
    pair = _matched_law_times(posterior, theta, decay)
    if pair is None:
        return trend, 0.0
    _, matched, close = pair
    omega = decay.scaling.omega
    n = np.arange(matched.size, dtype=float)
    uneven = matched - np.polyval(np.polyfit(n, matched, 1), n)
    beyond = turning_point_trend(
        np.asarray(times, dtype=float)[close] - uneven / omega,
        np.asarray(decay.peaks.value, dtype=float)[close],
    )
    half = np.diff(matched)
    law_change = float((half[-1] - half[1]) / np.mean(half)) if half.size >= 3 else 0.0
    if beyond is None or not math.isfinite(beyond.change):
        return trend, law_change
    return beyond, law_change


def _warn_frequency_trend(
    name: str | None,
    trend: FrequencyTrend | None,
    law: str,
    pendulum: float | None = None,
) -> None:
    """Say when the frequency is not constant along the decay beyond the law's own
    change (the nuisance that carries it is in the intervals); ``pendulum``: the change
    a pendulum's half period makes over the same swings (a run in radians with a linear
    restoring force), named when the measured change is the pendulum's."""
    if trend is None:
        return
    if abs(trend.change) > FREQUENCY_TREND_CHANGE and abs(trend.z) > FREQUENCY_TREND_Z:
        like = (
            "; if the spring stiffens or softens with the swing (a cubic, Duffing spring), "
            "--restoring duffing (sidecar 'restoring': 'duffing') measures its β from the "
            "half periods and the energy lost per cycle with its potential"
        )
        if pendulum is not None:
            se = abs(trend.change / trend.z)
            if abs(trend.change - pendulum) <= max(3.0 * se, 0.25 * abs(pendulum)):
                like = (
                    f"; it changes as a pendulum's does over these swings ({100 * pendulum:+.3f} "
                    "%): for a pendulum, --restoring pendulum (sidecar 'restoring': "
                    "'pendulum') measures the energy lost per cycle with its potential"
                )
        warnings.warn(
            f"the oscillation's half period changes by {100 * trend.change:+.3f} % from the "
            f"largest swing to the smallest of {name or 'the run'} ({trend.z:+.0f} "
            f"standard errors) beyond what the law {law} makes: a stiffness that depends "
            "on amplitude, or a dissipation that changes the period otherwise than the law "
            "does; the constant Ω of the fit is then an average, and the reported "
            "parameters and ΔE(A) carry a frequency nuisance of "
            f"± {100 * frequency_nuisance_sd(trend):.2g} % for it{like}",
            FrequencyTrendWarning,
            stacklevel=4,
        )


def _pendulum_change(run: Run, metadata: Mapping[str, Any], turning: NDArray) -> float | None:
    """The relative change of a pendulum's half period over the analysed turning points
    [-] (:func:`~bayestribo.signal.frequency.turning_point_trend` of the times a pendulum
    takes between them), for a run in radians whose restoring force is the default
    linear one; None otherwise."""
    if run.length_unit != "rad" or metadata.get("restoring") not in (None, "linear"):
        return None
    a = np.abs(np.asarray(turning, dtype=float))
    if a.size < 2 or not np.all(a < np.pi):
        return None
    # the turning times a pendulum would take between these turning points, measured
    # as the record's are (the trend's own model, linear in the swing, reads a
    # pendulum's quadratic change otherwise than its end points do)
    ratio = get_restoring("pendulum").half_period_ratio
    swing = 0.5 * (a[1:] + a[:-1])
    times = np.concatenate(([0.0], np.cumsum(ratio(swing))))
    found = turning_point_trend(times, turning)
    return None if found is None else float(found.change)


def _measured_restoring(name: str | None, decay: EnergyDecay) -> tuple[Any, dict | None]:
    """The run's restoring force, its parameters measured from the turning points where
    it has any (a Duffing spring's β), in the dimensionless unit of the decay, and the
    record of that measurement (None for a force without parameters).

    Raises
    ------
    BayestriboError
        When the record holds too few turning times to measure them.
    """
    restoring = get_restoring(name)
    if not restoring.fitted or restoring.measure is None:
        return restoring, None
    if decay.turning_times is None:
        raise BayestriboError(
            f"restoring force {restoring.name!r}: its parameters are measured from the "
            "turning times, which this record's analysis does not give"
        )
    try:
        measured, record = restoring.measure(
            decay.turning_times, decay.peaks.value / decay.scaling.length_scale
        )
    except ValueError as exc:
        raise BayestriboError(f"restoring force {restoring.name!r}: {exc}") from None
    return measured, record


def _restoring_scale(
    restoring: Any, scale: Any, turning_points: NDArray, measured: dict | None = None
) -> tuple[Any, float]:
    """The physical scale of the turning points' ΔE(A) under a restoring force, and the
    relative sd of its energy unit.

    The energy unit is κ = IΩ² with Ω the measured frequency; a pendulum's κ = Iω₀² takes
    its small-swing ω₀ = Ω T(A)/T₀, with the half period ratio at the median swing of
    the analysed half cycles; half the span of the ratio over them (twice, for Ω²) is
    its relative sd. A measured parameter's standard error (a Duffing spring's β) adds
    its effect on the loss at the largest swing, V'(A) = A + βA³: A²δβ/(1 + βA²)
    relative. A linear spring's scale is returned as it is."""
    a = np.abs(np.asarray(turning_points, dtype=float))
    energy_sd = 0.0
    if measured and "beta_se" in measured and a.size:
        top = float(np.max(a))
        beta, se = float(measured["beta"]), float(measured["beta_se"])
        energy_sd = top * top * se / max(1.0 + beta * top * top, 1e-12)
    if restoring.name == "linear" or scale.stiffness is None:
        return scale, energy_sd
    swing = 0.5 * (a[1:] + a[:-1]) if a.size > 1 else a
    ratio = restoring.half_period_ratio(swing)
    middle = float(np.median(ratio))
    spread = float(np.max(ratio) - np.min(ratio)) / middle
    stiffness = scale.stiffness * middle**2
    return dataclasses.replace(scale, stiffness=stiffness), math.hypot(spread, energy_sd)


def _warn_restoring(name: str | None, restoring: Any, law: str) -> None:
    """Say that the laws assume a linear restoring force when the run's is another."""
    if restoring.name == "linear":
        return
    warnings.warn(
        f"the restoring force of {name or 'the run'} is the {restoring.name}'s, and the law "
        f"{law} assumes a linear one: its parameters are not a measurement. The energy "
        "dissipated per cycle measured from the turning points with the "
        f"{restoring.name}'s potential (printed as 'turning points (law-free)') is the "
        "answer",
        MisfitWarning,
        stacklevel=4,
    )


def _flagged(misfit: tuple[float, int, float], shape: ShapeDeparture) -> bool:
    """True when :func:`_warn_misfit` has said the law misfits (or the discrepancy holds
    it)."""
    return bool(misfit[2] < MISFIT_P or shape.p_value < MISFIT_P)


def _warn_shape(
    name: str | None,
    agreement: dict[str, Any] | None,
    law: str,
    compared: bool,
    flagged: bool,
) -> None:
    """Say when the law's ΔE(A) has another shape than the turning points' ΔE(A)
    (:func:`~bayestribo.inference.dissipation.shape_agreement`): a friction law on a
    record of drag passes a χ² test when the noise is taken from a segment that still
    moves, but its ΔE(A) grows as A where the turning points' grows as A²."""
    if agreement is None or agreement["same_shape"] or flagged:
        return
    run = name or "the run"
    how = (
        f"its ΔE(A) grows as A^{agreement['law_slope']:.2f}, the turning points' as "
        f"A^{agreement['measured_slope']:.2f} ± {agreement['measured_slope_se']:.2f} "
        f"(departing by up to {agreement['max_percent']:.0f} %)"
    )
    if compared:
        text = (
            f"no law compared has the shape of the energy lost per cycle of {run}: the "
            f"best, {law}, {how}. The answer is the turning points' ΔE(A), whatever the "
            "law (printed as 'turning points (law-free)')"
        )
    else:
        text = (
            f"the law {law} has another shape than the energy lost per cycle of {run}: "
            f"{how}; its parameters are not a measurement. Fit with law='auto' (--law "
            "auto); the turning points' ΔE(A) (printed as 'turning points (law-free)') "
            "holds whatever the law"
        )
    warnings.warn(text, MisfitWarning, stacklevel=4)


def _warn_misfit(
    name: str | None,
    misfit: tuple[float, int, float],
    shape: ShapeDeparture,
    discrepancy: bool,
    law: str,
    compared: bool = False,
    half_cycles: int | None = None,
) -> None:
    """Say, with numbers, that the law misfits the run, and what to do (see
    :func:`summarise`); ``half_cycles``: how many the analysis holds (the law-free answer
    needs three, :func:`~bayestribo.inference.dissipation.turning_point_dissipation`)."""
    from bayestribo.inference.dissipation import FEWEST_HALF_CYCLES

    law_free = (
        "The answer is the energy dissipated per cycle measured from the turning points, "
        "whatever the law (result.turning_point_dissipation, printed as 'turning points "
        "(law-free)')"
    )
    if half_cycles is not None and half_cycles < FEWEST_HALF_CYCLES:
        law_free = (
            f"The analysis holds {half_cycles} half cycle(s), too few for the energy "
            "dissipated per cycle measured from the turning points either: the record "
            "holds no measurement of the dissipation; record more of the decay"
        )
    chi2, m, misfit_p = misfit
    shaped = bool(shape.p_value < MISFIT_P)
    if not (misfit_p < MISFIT_P or shaped):
        return
    run = name or "the run"
    how = f"χ² = {chi2:.0f} for {m} increments, p = {misfit_p:.1e}"
    if shaped:
        how = shape.describe() + f"; {how}"
    if discrepancy:
        if not shaped:
            return  # white misfit only: the discrepancy's white term carries it
        warnings.warn(
            f"the law {law} is not adequate for {run}: {how}. The discrepancy terms "
            "carry the departure into the intervals, so its parameters are the law's best "
            "constant values over this decay, not those of a law that holds at every "
            "amplitude (bayestribo check shows how they change along the decay)",
            MisfitWarning,
            stacklevel=4,
        )
        return
    if compared:
        warnings.warn(
            f"no law compared holds for {run}: the best, {law}, misfits it beyond its "
            f"noise ({how}); its parameters are not a measurement of any mechanism and its "
            f"intervals are too narrow. {law_free}",
            MisfitWarning,
            stacklevel=4,
        )
        return
    few = half_cycles is not None and half_cycles < FEWEST_HALF_CYCLES
    warnings.warn(
        f"the law {law} misfits {run} beyond its noise ({how}): its parameters are not "
        "a measurement and its intervals are too narrow. Fit with law='auto' "
        "(--law auto): it compares the registered laws and keeps one that holds"
        + (
            f". {law_free}"
            if few
            else "; the energy dissipated per cycle measured from the turning points "
            "(printed as 'turning points (law-free)') holds whatever the law"
        ),
        MisfitWarning,
        stacklevel=4,
    )


def _diagnostics(sampled: Sampled, misfit: tuple[float, int, float]) -> dict[str, Any]:
    names, s = sampled.posterior.names, sampled.run

    def by_name(values: NDArray) -> dict[str, float]:
        return dict(zip(names, np.asarray(values).tolist(), strict=True))

    chi2, m, p = misfit
    return {
        "converged": s.converged,
        "reasons": s.reasons,
        "n_walkers": sampled.settings.n_walkers,
        "n_ensembles": sampled.settings.n_ensembles,
        "n_steps": s.n_steps,
        "burn": s.burn,
        "thin": s.thin,
        "autocorr_time": by_name(s.autocorr_time),
        "autocorr_time_max": float(np.max(s.autocorr_time)),
        "ess": by_name(s.ess),
        "ess_min": float(np.min(s.ess)),
        "rhat": by_name(s.rhat),
        "rhat_max": float(np.max(s.rhat)),
        "acceptance_fraction": s.acceptance_fraction,
        "map": by_name(sampled.theta_map),
        "chi2_map": chi2,
        "n_increments": m,
        "misfit_p": p,
    }


def summarise(
    prepared: PreparedRun,
    sampled: Sampled,
    *,
    seed: int | np.random.Generator | None = None,
    recorded_seed: int | None = None,
    compared: bool = False,
) -> FitResult:
    """Step 4: derived quantities, diagnostics and checks, as a :class:`FitResult`.

    Parameters
    ----------
    prepared : PreparedRun
        From :func:`prepare`.
    sampled : Sampled
        From :func:`sample` on a posterior of ``prepared.data``.
    seed : int or Generator, optional
        Seed of the calibration nuisance and posterior predictive draws.
    recorded_seed : int, optional
        The seed of the whole fit, recorded in the result (-1 if none).
    compared : bool
        The law is the verdict of a comparison of laws (``law="auto"``): a misfit then
        says that no law compared holds, instead of advising the comparison.

    Returns
    -------
    FitResult

    Warns
    -----
    MisfitWarning
        When the MAP residuals exceed the noise (χ² p-value below 1e-3) and the
        posterior has no discrepancy term: the intervals are then too narrow; or when
        the residuals hold a smooth departure along the decay
        (:meth:`~bayestribo.inference.likelihood.PiLikelihood.shape_departure`, p below
        1e-3), with or without the discrepancy: the constant law is not adequate, and
        the message says by how much (the largest relative departure of the increments
        and its standard error). The result records the test in
        ``diagnostics["shape_departure"]``. A law chosen by a comparison
        (``compared``) that misfits says that no law compared holds.
    FrequencyTrendWarning
        When the half period changes with amplitude beyond the law's own change
        (:func:`~bayestribo.signal.frequency.turning_point_trend` of the decay's turning
        times, :func:`_beyond_the_law`: by more than 2e-4 at 4 standard errors): the
        reported ζ, μ_k, μ_s, ζ_k, d_k and ΔE(A) carry a frequency nuisance for it in
        any case (:func:`frequency_nuisance_sd`, recorded in the result's
        ``frequency_nuisance_sd`` attribute), so the intervals hold it.
    ConvergenceWarning
        When the sampler did not converge (the result says so too).
    PriorBoundWarning
        When a posterior piles on a physical upper bound of its prior
        (:func:`~bayestribo.inference.priors.piled_on_bounds`); the result records it in
        ``diagnostics["at_prior_bound"]`` and is not :attr:`~FitResult.usable`.
    """
    rng = np.random.default_rng(seed)
    # -- separated modes: not converged when a minor one matters (inference/modes.py) --
    sampled, modes = mode_check(sampled)
    # -- end of the mode check --
    posterior, run = sampled.posterior, sampled.run
    name = prepared.name
    discrepancy = any(
        n in posterior.names or n in posterior.fixed for n in ("log10_discrepancy", "log10_shape")
    )
    misfit = _misfit(posterior, sampled.theta_map)
    shape = _shape_departure(posterior, sampled.theta_map)
    half_cycles = int(prepared.decay.peaks.value.size) - 1
    _warn_misfit(name, misfit, shape, discrepancy, posterior.law.name, compared, half_cycles)
    flat = run.chains.reshape(-1, run.chains.shape[-1])
    at_bound = piled_on_bounds(flat, posterior.priors)
    for entry in at_bound:
        warnings.warn(
            f"{entry['parameter']} piles on the upper bound of its prior "
            f"({entry['bound']:.4g}; {100 * entry['fraction']:.0f} % of the draws within 1 % "
            f"of the range below it) for {name or 'the run'}: the prior, not the data, "
            "ends the interval, so this is no measurement. The default bounds are physical "
            "(the data then ask for a value the motion cannot have): check the units and "
            "the channels (bayestribo inspect) and that the record is a free decay; a "
            "narrowed prior: widen it",
            PriorBoundWarning,
            stacklevel=3,
        )
    decay = prepared.decay
    if decay.turning_times is not None:
        trend = turning_point_trend(decay.turning_times, decay.peaks.value)
    else:
        trend = frequency_trend(prepared.run.time, prepared.run.displacement, prepared.run.velocity)
    trend, law_change = _beyond_the_law(posterior, sampled.theta_map, trend, decay)
    pendulum = _pendulum_change(
        prepared.run, prepared.metadata, decay.peaks.value / decay.scaling.length_scale
    )
    _warn_frequency_trend(name, trend, posterior.law.name, pendulum)
    frequency_sd = frequency_nuisance_sd(trend)
    metadata = prepared.metadata
    scaling = prepared.decay.scaling
    # the sensor's gain (signal/sensor.py): its own stream, so that the draws of the
    # other nuisances and of the predictive Π do not move with it
    sensor = sensor_calibration(
        metadata,
        scaling.omega / (2.0 * np.pi),
        displacement=prepared.run.displacement is not None,
        velocity=prepared.run.velocity is not None,
    )
    gain = sensor.draws(rng.spawn(1)[0], flat.shape[0])
    derived = derived_quantities(posterior, flat, scaling, metadata, rng, frequency_sd, gain)
    scale = physical_scale(scaling, metadata)
    own, own_units = law_quantities(posterior, flat, scale, gain)
    derived = {**derived, **{k: v for k, v in own.items() if k not in derived}}
    swings = dissipation_amplitudes(decay.peaks.value / scaling.length_scale)
    scale = dataclasses.replace(scale, length_scale=scale.length_scale / sensor.gain)
    dissipation = dissipation_band(
        posterior, flat, swings, scale, frequency_sd=frequency_sd, gain_sd=sensor.gain_sd
    )
    restoring, measured_spring = _measured_restoring(metadata.get("restoring"), decay)
    tp_scale, energy_sd = _restoring_scale(
        restoring, scale, decay.peaks.value / scaling.length_scale, measured_spring
    )
    measured = turning_point_dissipation(
        decay.peaks.value / scaling.length_scale,
        swings,
        tp_scale,
        gain_sd=sensor.gain_sd,
        restoring=restoring,
        energy_sd=energy_sd,
    )
    _warn_restoring(name, restoring, posterior.law.name)
    agreement = shape_agreement(dissipation, measured)
    _warn_shape(name, agreement, posterior.law.name, compared, flagged=_flagged(misfit, shape))
    noise_info = {**prepared.noise.to_dict(), "description": prepared.noise.describe()}
    attrs = {
        "run_name": name,
        "model": posterior.likelihood.model,
        "law": posterior.law.name,
        "dissipation_json": json.dumps(plain_data(dissipation)),
        "turning_point_dissipation_json": json.dumps(plain_data(measured)),
        "shape_agreement_json": json.dumps(plain_data(agreement)),
        "restoring_json": json.dumps(
            plain_data({"name": restoring.name, **(measured_spring or {})})
        ),
        "units_json": json.dumps(own_units),
        "seed": -1 if recorded_seed is None else int(recorded_seed),
        "package_version": __version__,
        "friction_defined": int(scaling.friction_defined),
        "length_scale": scaling.length_scale,
        "omega": scaling.omega,
        "tau_end": prepared.data.tau_end,
        "motion_ended": int(prepared.data.motion_ended),
        "metadata_json": json.dumps(plain_data(metadata)),
        "noise_json": json.dumps(plain_data(noise_info)),
        "channels_json": json.dumps(plain_data(prepared.channels)),
        "priors_json": json.dumps(posterior.priors.to_spec()),
        "fixed_json": json.dumps(plain_data(posterior.fixed)),
        "settings_json": json.dumps(
            {
                "grid_points": prepared.grid_points,
                "skip_oscillations": prepared.skip_oscillations,
                "discrepancy": discrepancy,
                "notch_Hz": list(prepared.decay.notch_Hz),
                "max_steps": sampled.settings.max_steps,
            }
        ),
        "diagnostics_json": json.dumps(
            plain_data(
                {
                    **_diagnostics(sampled, misfit),
                    "shape_departure": shape.to_dict(),
                    "at_prior_bound": at_bound,
                    "modes": modes.to_dict(),  # the mode check (inference/modes.py)
                    "surrogate": None if sampled.surrogate is None else sampled.surrogate.to_dict(),
                }
            )
        ),
        "frequency_trend_json": json.dumps(None if trend is None else trend.to_dict()),
        "frequency_nuisance_sd": frequency_sd,
        "sensor_json": json.dumps({**dataclasses.asdict(sensor), "description": sensor.describe()}),
        "law_frequency_change": law_change,
        "prior_sensitivity_json": json.dumps(plain_data(prior_sensitivity(flat, posterior.priors))),
    }
    # the pointwise log-likelihood (PSIS-LOO) of the density the chains sampled: the
    # surrogate's where its check passed (inference/surrogate.py)
    # the sampler's own statistics (ArviZ's sample_stats), where they match the draws
    lp = run.log_prob if np.shape(run.log_prob) == run.chains.shape[:2] else None
    result = FitResult(
        draws=fit_draws(
            sampled.draws_posterior,
            run.chains,
            derived,
            rng,
            attrs,
            log_prob=lp,
            walker_acceptance=run.walker_acceptance,
        )
    )
    if not run.converged:
        warnings.warn(
            f"the sampler did not converge on {name or 'the run'}: " + "; ".join(run.reasons),
            ConvergenceWarning,
            stacklevel=3,
        )
    return result
