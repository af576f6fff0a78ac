"""The summarise stage: a checked sample becomes a :class:`FitResult`.

:func:`summary` takes the prepared run, its sampled posterior and the checks of the
check stage (:func:`bayestribo.inference.checks.check`, run here when not given) and
gives a :class:`Summary`: the fit's :class:`~bayestribo.inference.fit_record.FitRecord`
(derived quantities' draws aside: the law's ΔE(A) band and the turning points'
(law-free) ΔE(A), diagnostics, provenance) and its draws. :meth:`Summary.result` makes
the :class:`~bayestribo.inference.result.FitResult`, writing the record once;
:func:`summarise` is the two in a row. ``law="auto"`` completes the record before the
result is made (:mod:`bayestribo.inference.auto`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo import __version__
from bayestribo._warnings import warn
from bayestribo.errors import BayestriboError, ConvergenceWarning, MisfitWarning
from bayestribo.inference.assemble import FitDraws, derived_quantities, fit_draws
from bayestribo.inference.checks import FitChecks, Misfit, check, warn_shape
from bayestribo.inference.dissipation import (
    dissipation_amplitudes,
    dissipation_band,
    law_quantities,
    physical_scale,
    shape_agreement,
    turning_point_dissipation,
)
from bayestribo.inference.fit_record import FitRecord, plain_data
from bayestribo.inference.law_free import STAIRCASE, law_free_turning_points, warn_energy_gain
from bayestribo.inference.nominal_frequency import warn_nominal_frequency
from bayestribo.inference.plausibility import warn_implausible_friction
from bayestribo.inference.restoring_error import restoring_error, shifted
from bayestribo.inference.result import FitResult
from bayestribo.inference.sensitivity import prior_sensitivity
from bayestribo.inference.types import PreparedRun, Sampled
from bayestribo.model.restoring import get_restoring
from bayestribo.signal.decay import EnergyDecay
from bayestribo.signal.sensor import gain_variance_share, sensor_calibration

__all__ = ["Summary", "summarise", "summary"]


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
    restoring: Any,
    scale: Any,
    turning_points: NDArray,
    measured: dict | None = None,
    small_swings: bool = False,
) -> tuple[Any, float]:
    """The physical scale of the turning points' ΔE(A) under a restoring force, and the
    relative sd of its energy unit.

    The energy unit is κ = IΩ² with Ω the measured frequency; a pendulum's κ = Iω₀² takes
    its small-swing ω₀ = Ω T(A)/T₀, with the half period ratio at the median swing of
    the analysed half cycles; half the span of the ratio over them (twice, for Ω²) is
    its relative sd. A measured parameter's standard error (a Duffing spring's β) adds
    its effect on the loss at the largest swing, V'(A) = A + βA³: A²δβ/(1 + βA²)
    relative. A linear spring's scale is returned as it is, and so is one whose Ω is
    already the small swings' (``small_swings``: a run prepared with its restoring
    force's potential, :func:`bayestribo.inference.preparation.small_swing_frequency`)."""
    a = np.abs(np.asarray(turning_points, dtype=float))
    energy_sd = 0.0
    if measured and "beta_se" in measured and a.size:
        top = float(np.max(a))
        beta, se = float(measured["beta"]), float(measured["beta_se"])
        energy_sd = top * top * se / max(1.0 + beta * top * top, 1e-12)
    if restoring.name == "linear" or scale.stiffness is None or small_swings:
        return scale, energy_sd
    swing = 0.5 * (a[1:] + a[:-1]) if a.size > 1 else a
    ratio = restoring.half_period_ratio(swing)
    middle = float(np.median(ratio))
    spread = float(np.max(ratio) - np.min(ratio)) / middle
    stiffness = scale.stiffness * middle**2
    return dataclasses.replace(scale, stiffness=stiffness), math.hypot(spread, energy_sd)


def _warn_restoring(name: str | None, restoring: Any, law: Any) -> None:
    """Say that the law assumes a linear restoring force when the run's is another that
    the law's model does not take (a force registered without compiled kernels)."""
    if restoring.name == "linear" or law.restoring is not None:
        return
    warn(
        f"the restoring force of {name or 'the run'} is the {restoring.name}'s, and the law "
        f"{law.name} assumes a linear one: its parameters are not a measurement. The energy "
        "dissipated per cycle measured from the turning points with the "
        f"{restoring.name}'s potential (printed as 'turning points (law-free)') is the "
        "answer",
        MisfitWarning,
    )


def _diagnostics(sampled: Sampled, misfit: Misfit) -> dict[str, Any]:
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
        # the independence move's weight in the kernel of the draws kept, and the step
        # it was taken out at where it did not mix (inference/sampling.py)
        "independence_weight": s.independence,
        "independence_dropped": s.independence_dropped,
        "map": by_name(sampled.theta_map),
        "chi2_map": chi2,
        "n_increments": m,
        "misfit_p": p,
    }


@dataclass(frozen=True)
class Summary:
    """A summarised fit before it is a :class:`FitResult`: its record and its draws.

    Attributes
    ----------
    record : FitRecord
        What the fit records (:mod:`bayestribo.inference.fit_record`).
    draws : FitDraws
        The draws of every quantity, the pointwise log-likelihood and the predictive
        draws (:class:`~bayestribo.inference.assemble.FitDraws`; its attributes are the
        record's, written by :meth:`result`).
    """

    record: FitRecord
    draws: FitDraws

    def result(self) -> FitResult:
        """The :class:`FitResult`: the draws, with the record as their attributes."""
        return FitResult(draws=self.draws.with_attrs(self.record.to_attrs()))


def summarise(
    prepared: PreparedRun,
    sampled: Sampled,
    *,
    seed: int | np.random.Generator | None = None,
    recorded_seed: int | None = None,
    compared: bool = False,
    checks: FitChecks | None = None,
) -> FitResult:
    """Derived quantities, diagnostics and checks, as a :class:`FitResult`
    (:func:`summary` made a result; the parameters and warnings are its)."""
    return summary(
        prepared,
        sampled,
        seed=seed,
        recorded_seed=recorded_seed,
        compared=compared,
        checks=checks,
    ).result()


def summary(
    prepared: PreparedRun,
    sampled: Sampled,
    *,
    seed: int | np.random.Generator | None = None,
    recorded_seed: int | None = None,
    compared: bool = False,
    checks: FitChecks | None = None,
) -> Summary:
    """Derived quantities, diagnostics and checks: the record and draws of a fit.

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
    checks : FitChecks, optional
        The check stage's findings (:func:`bayestribo.inference.checks.check`, with the
        same ``compared``); made here when not given.

    Returns
    -------
    Summary
        Its :meth:`~Summary.result` is the :class:`FitResult`.

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
        ``frequency_nuisance_sd`` attribute), so the intervals hold it. On the linear
        spring with a law of constant half period (a closed form) it is a
        :class:`~bayestribo.errors.LinearSpringWarning` (also a MisfitWarning: the
        command line exits 1), naming the restoring force to try.
    ConvergenceWarning
        When the sampler did not converge (the result says so too).
    ImplausibleFrictionWarning
        When μ_k's interval lies wholly above any contact's kinetic friction
        coefficient (:mod:`bayestribo.inference.plausibility`): the load or the mass is
        in another unit (a MisfitWarning: the command line exits 1).
    NominalFrequencyWarning
        When the natural frequency measured from the record is more than 1 % from the
        nominal ``natural_frequency_Hz`` given with a mass
        (:mod:`bayestribo.inference.nominal_frequency`): the stiffness takes the
        measured one, wrong where the record's clock is off (a MisfitWarning: exit 1).
    PriorBoundWarning
        When a posterior piles on a physical upper bound of its prior
        (:func:`~bayestribo.inference.priors.piled_on_bounds`); the result records it in
        ``diagnostics["at_prior_bound"]`` and is not :attr:`~FitResult.usable`.
    """
    rng = np.random.default_rng(seed)
    if checks is None:
        checks = check(prepared, sampled, compared=compared)
    sampled = checks.sampled
    posterior, run = sampled.posterior, sampled.run
    name = prepared.name
    discrepancy = checks.discrepancy
    flat = run.chains.reshape(-1, run.chains.shape[-1])
    decay = prepared.decay
    trend, law_change, frequency_sd = checks.trend, checks.law_change, checks.frequency_sd
    metadata = prepared.metadata
    scaling = prepared.decay.scaling
    # the sensor's gain (signal/sensor.py): its own stream, so that the draws of the
    # other nuisances and of the predictive Π do not move with it
    sensor = sensor_calibration(
        metadata,
        scaling.omega / (2.0 * np.pi),
        displacement=prepared.run.displacement is not None,
        velocity=prepared.run.velocity is not None,
        filter_undone=prepared.filter_undone,
    )
    gain = sensor.draws(rng.spawn(1)[0], flat.shape[0])
    # a measured restoring force's error (a Duffing spring's β), marginalised into the
    # draws the intervals and the law's ΔE(A) are taken from; its own stream, so that
    # the other nuisances' draws do not move with it
    spring_error = restoring_error(prepared, posterior, flat, rng.spawn(1)[0])
    reported = shifted(flat, spring_error)
    derived = derived_quantities(posterior, reported, scaling, metadata, rng, frequency_sd, gain)
    scale = physical_scale(scaling, metadata)
    own, own_units = law_quantities(posterior, reported, scale, gain)
    derived = {**derived, **{k: v for k, v in own.items() if k not in derived}}
    warn_implausible_friction(name, derived, metadata)
    warn_nominal_frequency(name, decay, metadata)
    # the law-free answer's turning points: a coarse displacement's from its staircase
    # (inference/law_free.py); the swings span them
    turning, staircase = law_free_turning_points(prepared)
    swings = dissipation_amplitudes(turning)
    scale = dataclasses.replace(scale, length_scale=scale.length_scale / sensor.gain)
    dissipation = dissipation_band(
        posterior, reported, swings, scale, frequency_sd=frequency_sd, gain_sd=sensor.gain_sd
    )
    restoring, measured_spring = _measured_restoring(metadata.get("restoring"), decay)
    tp_scale, energy_sd = _restoring_scale(
        restoring,
        scale,
        decay.peaks.value / scaling.length_scale,
        measured_spring,
        small_swings=decay.restoring is not None,
    )
    measured = turning_point_dissipation(
        turning,
        swings,
        tp_scale,
        gain_sd=sensor.gain_sd,
        restoring=restoring,
        energy_sd=energy_sd,
    )
    if measured is not None and staircase:
        measured["definition"] += f"; {STAIRCASE}"
    warn_energy_gain(name, measured)
    _warn_restoring(name, restoring, posterior.law)
    agreement = shape_agreement(dissipation, measured)
    warn_shape(name, agreement, posterior.law.name, compared, flagged=checks.flagged)
    noise_info = {**prepared.noise.to_dict(), "description": prepared.noise.describe()}
    if decay.wander_floor is not None and decay.noise_colour is not None:
        # the analysis ended above low-frequency noise at rest (signal/noise_colour.py)
        noise_info["low_frequency"] = {
            **dataclasses.asdict(decay.noise_colour),
            "description": decay.noise_colour.describe(),
            "smallest_swing_analysed": decay.wander_floor,
            "analysis_end_s": decay.end_time,
        }
        noise_info["description"] += (
            f"; {decay.noise_colour.name} noise at rest (spectral slope "
            f"{decay.noise_colour.slope:.2f}): the analysis ends at t = {decay.end_time:.6g} s, "
            f"the swings below {decay.wander_floor:.3g} left out"
        )
    diagnostics = {
        **_diagnostics(sampled, checks.misfit),
        "shape_departure": checks.shape.to_dict(),
        "at_prior_bound": checks.at_bound,
        "modes": checks.modes.to_dict(),  # the mode check (inference/modes.py)
        "surrogate": None if sampled.surrogate is None else sampled.surrogate.to_dict(),
    }
    record = FitRecord(
        run_name=name,
        model=posterior.likelihood.model,
        law=posterior.law.name,
        dissipation=plain_data(dissipation),
        turning_point_dissipation=plain_data(measured),
        shape_agreement=plain_data(agreement),
        restoring=plain_data(
            {
                "name": restoring.name,
                **(measured_spring or {}),
                **({} if spring_error is None else {"error": spring_error.to_dict()}),
                # the law's model takes its potential (model/laws/nonlinear.py)
                "in_model": posterior.law.restoring is not None,
                # restoring "auto": the force chosen and why (inference/restoring_choice.py)
                **(
                    {}
                    if prepared.restoring_choice is None
                    else {
                        "auto": {
                            **prepared.restoring_choice.to_dict(),
                            "description": prepared.restoring_choice.describe(),
                        }
                    }
                ),
            }
        ),
        units=own_units,
        seed=-1 if recorded_seed is None else int(recorded_seed),
        package_version=__version__,
        friction_defined=int(scaling.friction_defined),
        length_scale=scaling.length_scale,
        omega=scaling.omega,
        tau_end=prepared.data.tau_end,
        motion_ended=int(prepared.data.motion_ended),
        metadata=plain_data(metadata),
        noise=plain_data(noise_info),
        channels=plain_data(prepared.channels),
        priors=posterior.priors.to_spec(),
        fixed=plain_data(posterior.fixed),
        settings={
            "grid_points": prepared.grid_points,
            "skip_oscillations": prepared.skip_oscillations,
            "discrepancy": discrepancy,
            "notch_Hz": list(prepared.decay.notch_Hz),
            "max_steps": sampled.settings.max_steps,
        },
        diagnostics=plain_data(diagnostics),
        frequency_trend=None if trend is None else trend.to_dict(),
        frequency_nuisance_sd=frequency_sd,
        sensor={
            **dataclasses.asdict(sensor),
            "description": sensor.describe(),
            "variance_share": gain_variance_share(derived, gain),
        },
        law_frequency_change=law_change,
        prior_sensitivity=plain_data(prior_sensitivity(flat, posterior.priors)),
    )
    # the pointwise log-likelihood (PSIS-LOO) of the density the chains sampled: the
    # surrogate's where its check passed (inference/surrogate.py)
    # the sampler's own statistics (ArviZ's sample_stats), where they match the draws
    lp = run.log_prob if np.shape(run.log_prob) == run.chains.shape[:2] else None
    if lp is not None and sampled.log_prob_deferred is not None:
        lp = sampled.log_prob_deferred  # draws mixed in at a boundary: computed when read
    draws = fit_draws(
        sampled.draws_posterior,
        run.chains,
        derived,
        rng,
        {},
        log_prob=lp,
        walker_acceptance=run.walker_acceptance,
    )
    if not run.converged:
        warn(
            f"the sampler did not converge on {name or 'the run'}: " + "; ".join(run.reasons),
            ConvergenceWarning,
        )
    return Summary(record, draws)
