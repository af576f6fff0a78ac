"""The check stage: is the sampled law adequate for the run, and is the sample sound?

:func:`check` takes the prepared run (:class:`~bayestribo.inference.types.PreparedRun`)
and its sampled posterior (:class:`~bayestribo.inference.types.Sampled`) and gives a
:class:`FitChecks`: separated modes (:mod:`bayestribo.inference.modes`), the misfit of
the optimum's residuals (:func:`misfit_p_value`) and their smooth departure along the
decay, posteriors piled on a prior's bound, and the half period's trend with amplitude
beyond the law's own (:func:`frequency_nuisance_sd`, the nuisance the summarise stage
carries into the intervals). Each finding is warned about here, with numbers and what
to do; :func:`warn_shape` is the check of the law's ΔE(A) against the turning points',
which the summarise stage calls once it has both.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any, NamedTuple

import numpy as np
import scipy.stats
from numpy.typing import NDArray

from bayestribo._warnings import warn
from bayestribo.errors import (
    ArmNoiseWarning,
    FrequencyTrendWarning,
    HighPassWarning,
    LinearSpringWarning,
    MisfitWarning,
    PriorBoundWarning,
)
from bayestribo.inference.dissipation import FEWEST_HALF_CYCLES
from bayestribo.inference.identifiability import unidentified_reasons
from bayestribo.inference.likelihood import ShapeDeparture
from bayestribo.inference.modes import ModeReport, mode_check
from bayestribo.inference.posterior import Posterior
from bayestribo.inference.preparation import matched_law_times
from bayestribo.inference.priors import piled_on_bounds, widened_prior
from bayestribo.inference.restoring_choice import (
    RestoringChoice,
    arm_advice,
    choose_restoring,
    simple_pendulum_arm,
)
from bayestribo.inference.stop_prior import StopBeyondPrior, stop_beyond_prior
from bayestribo.inference.types import MISFIT_P, PreparedRun, Sampled
from bayestribo.io.run import Run
from bayestribo.model.restoring import get_restoring
from bayestribo.signal.decay import EnergyDecay
from bayestribo.signal.frequency import (
    FREQUENCY_TREND_CHANGE,
    FREQUENCY_TREND_Z,
    FrequencyTrend,
    frequency_trend,
    turning_point_trend,
)
from bayestribo.signal.high_pass import CALIBRATED_CORNER, HighPassSign, detect_high_pass
from bayestribo.signal.noise_colour import misfit_note

__all__ = [
    "FREQUENCY_TREND_CHANGE",
    "FREQUENCY_TREND_Z",
    "FitChecks",
    "Misfit",
    "check",
    "drag_change",
    "frequency_nuisance_sd",
    "misfit",
    "misfit_of_the_law",
    "misfit_p_value",
    "shape_departure",
    "warn_shape",
]


class Misfit(NamedTuple):
    """The χ² of the standardized residuals at the optimum and its p-value."""

    chi2: float
    n_increments: int
    p_value: float


@dataclass(frozen=True)
class FitChecks:
    """What the check stage found.

    Attributes
    ----------
    sampled : Sampled
        The sampled posterior as checked: not converged where a minor mode matters,
        its burn-in extended past a transient (:func:`~bayestribo.inference.modes.
        mode_check`); a run not converged names the parameters a term whose force the
        draws reach zero leaves unidentified (:func:`~bayestribo.inference.
        identifiability.unidentified_reasons`).
    modes : ModeReport
        The mode check.
    discrepancy : bool
        The posterior has the model-discrepancy terms.
    misfit : Misfit
        χ², increments and p-value of the residuals at the optimum.
    shape : ShapeDeparture
        The smooth departure of the decay from the law at the optimum.
    at_bound : list of dict
        Parameters piled on an upper bound of their prior
        (:func:`~bayestribo.inference.priors.piled_on_bounds`).
    trend : FrequencyTrend or None
        The half period's trend with amplitude beyond the law's own.
    law_change : float
        The law's own relative change of the half period over the decay [-].
    frequency_sd : float
        Relative sd of the frequency nuisance the trend asks for [-].
    """

    sampled: Sampled
    modes: ModeReport
    discrepancy: bool
    misfit: Misfit
    shape: ShapeDeparture
    at_bound: list[dict[str, Any]]
    trend: FrequencyTrend | None
    law_change: float
    frequency_sd: float

    @property
    def flagged(self) -> bool:
        """True when the misfit warning has said the law misfits (or the discrepancy
        holds a white misfit): the shape warning then adds nothing."""
        return _flagged(self.misfit, self.shape)


def check(prepared: PreparedRun, sampled: Sampled, *, compared: bool = False) -> FitChecks:
    """The checks of a sampled fit, each warned about.

    Parameters
    ----------
    prepared : PreparedRun
        From :func:`bayestribo.inference.preparation.prepare`.
    sampled : Sampled
        From :func:`bayestribo.inference.chains.sample` on a posterior of
        ``prepared.data``.
    compared : bool
        The law is the verdict of a comparison of laws (``law="auto"``): a misfit then
        says that no law compared holds, instead of advising the comparison.

    Returns
    -------
    FitChecks

    Warns
    -----
    MisfitWarning, PriorBoundWarning, FrequencyTrendWarning, LinearSpringWarning
        As :func:`bayestribo.inference.summarising.summarise` lists them.
    """
    # -- separated modes: not converged when a minor one matters (inference/modes.py) --
    sampled, modes = mode_check(sampled)
    # -- end of the mode check --
    posterior, run = sampled.posterior, sampled.run
    if not run.converged:
        # a term whose force the draws put at zero, or no more increments than
        # parameters: they are not identified, which says why the walkers did not
        # converge (inference/identifiability.py; a run stopped on that ridge says so
        # already)
        flat_draws = run.chains.reshape(-1, run.chains.shape[-1])
        n_increments = int(np.asarray(posterior.likelihood.data.increments).size) or None
        unseen = [
            reason
            for reason in unidentified_reasons(flat_draws, run.names, posterior.law, n_increments)
            if reason not in run.reasons
        ]
        if unseen:
            run = replace(run, reasons=[*run.reasons, *unseen])
            sampled = replace(sampled, run=run)
    name = prepared.name
    discrepancy = any(
        n in posterior.names or n in posterior.fixed for n in ("log10_discrepancy", "log10_shape")
    )
    found = misfit(posterior, sampled.theta_map)
    shape = shape_departure(posterior, sampled.theta_map)
    half_cycles = int(prepared.decay.peaks.value.size) - 1
    arm = _simple_pendulum_arm(prepared)
    high_pass = _high_pass_sign(prepared)
    corner = _high_corner(prepared)
    if corner is not None:
        warn(
            f"{name or 'the run'}: the sensor's high-pass declared at {corner:.2g} times the "
            f"oscillation's frequency, beyond the {CALIBRATED_CORNER:g} at which undone "
            "records were measured to give intervals that cover: the inverse multiplies "
            "the integral's error at the release and the noise's random walk by the corner "
            "(at 0.3 times the frequency 3 of 8 intervals of ζ missed, their z spread 1.65 "
            "times the intervals' width), so the "
            "law's intervals may be too narrow; the energy dissipated per cycle measured "
            "from the turning points (printed as 'turning points (law-free)') holds "
            "whatever the law, and a sensor with a lower corner gives a measurement",
            HighPassWarning,
        )
    grown = _arm_noise_growth(prepared.run)
    if grown is not None:
        warn(
            f"{name or 'the run'} is a length read as a pendulum's angle "
            f"(pendulum_radius_m) that swings to {grown[0]:.0f}°: its noise grows as "
            f"1/cos θ, to {grown[1]:.2f}× its value at rest there, and the fit takes it as "
            "at rest, so the law's intervals are not calibrated (beyond 48°; at 60° 4 of "
            "10 intervals of ζ missed the truth); the energy dissipated per cycle measured "
            "from the turning points (printed as 'turning points (law-free)') is the answer",
            ArmNoiseWarning,
        )
    flat = run.chains.reshape(-1, run.chains.shape[-1])
    at_bound = piled_on_bounds(flat, posterior.priors)
    widen = {
        str(e["parameter"]): option
        for e in at_bound
        if (option := widened_prior(str(e["parameter"]), posterior.priors[str(e["parameter"])]))
    }
    # a record that stops where no draw can (its stop needs a μ_s/μ_k beyond the
    # prior's bound, which the posterior presses on without piling on it): the bound is
    # the cause, and the prior that holds the stop is advised first
    stop = (
        stop_beyond_prior(posterior, flat, *_last_turns(prepared.decay))
        if prepared.data.motion_ended and prepared.decay.peaks.value.size
        else None
    )
    if stop is not None:
        widen["mu_s_ratio"] = stop.option
    # a misfit that is the law's (a smooth departure along the decay: the decay loses
    # energy with another shape than the law's) is answered by another law before a
    # wider prior or another spring (benchmarks/README.md, advice followed)
    laws = misfit_of_the_law(found, shape)
    _warn_misfit(
        name,
        found,
        shape,
        discrepancy,
        posterior.law.name,
        compared,
        half_cycles,
        arm=arm,
        grown=grown,
        widen=widen,
        high_pass=high_pass,
        prior_first=bool(prepared.data.motion_ended) and (not laws or stop is not None),
        stop=stop,
        noise_note=misfit_note(
            prepared.decay.noise_colour, prepared.decay.wander_floor, prepared.decay.peaks.value
        ),
    )
    for entry in at_bound:
        option = widen.get(str(entry["parameter"]))
        advice = (
            "The default bounds are physical (the data then ask for a value the motion "
            "cannot have): check the units and the channels (bayestribo inspect) and that "
            "the record is a free decay; a narrowed prior: widen it"
            if option is None
            else "Its bound is a belief, not a physical limit (a contact may stick at "
            f"more): where the stop is real, widen it ({_prior_spellings(option)})"
        )
        warn(
            f"{entry['parameter']} piles on the upper bound of its prior "
            f"({entry['bound']:.4g}; {100 * entry['fraction']:.0f} % of the draws within 1 % "
            f"of the range below it) for {name or 'the run'}: the prior, not the data, "
            f"ends the interval, so this is no measurement. {advice}",
            PriorBoundWarning,
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
    chosen = prepared.restoring_choice is not None
    _warn_frequency_trend(
        name,
        trend,
        posterior.law.name,
        pendulum,
        restoring=posterior.law.restoring,
        chosen=chosen,
        constant_period=posterior.law.closed_form,
        arm=arm,
        drag=laws and not compared and drag_change(trend, decay.peaks.value),
        spring=(
            _spring_of(prepared)
            if trend is not None
            and trend.significant
            and posterior.law.restoring is None
            and not chosen
            else None
        ),
    )
    return FitChecks(
        sampled,
        modes,
        discrepancy,
        found,
        shape,
        at_bound,
        trend,
        law_change,
        frequency_nuisance_sd(trend),
    )


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


def misfit(posterior: Posterior, theta: NDArray) -> Misfit:
    """χ², number of increments and p-value of the standardized residuals at θ
    (:func:`misfit_p_value`, with the degrees of freedom of the measured noise)."""
    resid = posterior.standardized_residuals(theta[None])[0]
    chi2 = float(np.sum(resid * resid))
    preparation = posterior.likelihood.data.preparation or {}
    noise = preparation.get("noise")
    dof = getattr(noise, "measured_dof", None)
    return Misfit(chi2, int(resid.size), misfit_p_value(chi2, int(resid.size), dof))


def shape_departure(posterior: Posterior, theta: NDArray) -> ShapeDeparture:
    """The smooth departure of the decay from the law at θ (noise variances alone)."""
    params = posterior.physical(theta[None])["params"]
    return posterior.likelihood.shape_departure({k: float(v[0]) for k, v in params.items()})


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


#: The share of a misfit's χ² beyond its expectation (χ² − m) that a smooth departure
#: along the decay must hold for the misfit to be the law's (:func:`misfit_of_the_law`).
LAW_MISFIT_SHARE = 0.5

#: A dissipation changes the half period at second order in its damping ratio ζ_e
#: (the damped half period of a linear oscillator, π/(Ω√(1 - ζ²)), changes by about
#: ζ²/2); a change up to this many times ζ_e² at the record's first swings is one a
#: drag can make (:func:`drag_change`) [-].
DRAG_CHANGE_FACTOR = 2.0


def misfit_of_the_law(misfit: Misfit, shape: ShapeDeparture) -> bool:
    """True when the law misfits and the misfit is the law's: a smooth departure of the
    increments along the decay (:meth:`~bayestribo.inference.likelihood.PiLikelihood.
    shape_departure`: the decay loses its energy with another shape than the law's)
    holds more than :data:`LAW_MISFIT_SHARE` of the χ² beyond its expectation.

    A stop the law cannot hold (μ_s/μ_k piled on its prior's bound, the pin at rest
    further off centre than the law lets it stick) misfits in the increments about the
    stop, not along the decay: on the paper's rig at μ_s/μ_k = 15-30 (an independent
    ``solve_ivp`` record, seeds 1-3) the smooth departure held 0.5-2.8 % of a χ² of
    800-10 000 (significant in 5 of 6 at 15 and 20); on a drag's record (quadratic drag,
    or damping growing with the swing) it held 97 %.

    Parameters
    ----------
    misfit : Misfit
        χ², increments and p-value at the optimum (:func:`misfit`).
    shape : ShapeDeparture
        The smooth departure at the optimum (:func:`shape_departure`).

    Returns
    -------
    bool
    """
    if not _flagged(misfit, shape) or not math.isfinite(shape.chi2):
        return False
    excess = misfit.chi2 - misfit.n_increments
    return bool(shape.p_value < MISFIT_P and shape.chi2 > LAW_MISFIT_SHARE * excess)


def drag_change(trend: FrequencyTrend | None, turning: NDArray) -> bool:
    """True when the half period's change along the decay is one a drag of the
    record's damping makes: it shortens as the swing decays (a damping that grows with
    the swing, the equivalent ζ_e larger at the large swings) by at most
    :data:`DRAG_CHANGE_FACTOR` ζ_e², ζ_e from the first swings' logarithmic decrement,
    ln(|Y_0|/|Y_k|)/(πk) over k ≤ 4 half cycles (quadratic drag on the paper's rig:
    −0.024 % at ζ_e = 0.014, where 2ζ_e² is 0.039 %). A spring that stiffens
    lengthens it as the swing decays; one that softens beyond a drag's change is the
    spring's.

    Parameters
    ----------
    trend : FrequencyTrend or None
        The change beyond the law (:func:`~bayestribo.signal.frequency.
        turning_point_trend`).
    turning : ndarray
        The analysed turning points about the equilibrium, in order (any unit).

    Returns
    -------
    bool
    """
    if trend is None or not math.isfinite(trend.change) or trend.change >= 0.0:
        return False
    a = np.abs(np.asarray(turning, dtype=float))
    k = min(4, a.size - 1)
    if k < 1 or not (a[0] > a[k] > 0.0):
        return False
    zeta = math.log(a[0] / a[k]) / (math.pi * k)
    return bool(abs(trend.change) <= DRAG_CHANGE_FACTOR * zeta * zeta)


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
    pair = matched_law_times(posterior, theta, decay)
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
    restoring: Any = None,
    chosen: bool = False,
    constant_period: bool = False,
    arm: float | None = None,
    drag: bool = False,
    spring: RestoringChoice | None = None,
) -> None:
    """Say when the frequency is not constant along the decay beyond the law's own
    change (the nuisance that carries it is in the intervals); ``pendulum``: the change
    a pendulum's half period makes over the same swings (a run in radians with a linear
    restoring force), named when the measured change is the pendulum's; ``restoring``:
    the law's nonlinear restoring force, named instead of a force to try; ``chosen``:
    the force was chosen by ``restoring="auto"`` (which has said why), none is advised;
    ``constant_period``: the law's half period is constant on the linear spring (a
    closed form: viscous damping and Coulomb friction, Eq. 15), so any change beyond the
    noise is not the law's: a :class:`~bayestribo.errors.LinearSpringWarning`, a misfit.
    A law without a closed form (a drag, a hysteretic loss) has its own change taken
    off first, and what it leaves is a
    :class:`~bayestribo.errors.FrequencyTrendWarning` that the nuisance carries, as on a
    nonlinear restoring force. ``arm``: the length of a simple pendulum recorded as a
    length whose half periods follow the record's (:func:`~bayestribo.inference.
    restoring_choice.simple_pendulum_arm`), advised instead of any force of x;
    ``drag``: the law misfits the decay as another law would not and the change is one
    a drag makes (:func:`misfit_of_the_law`, :func:`drag_change`): another law is
    advised first, the spring after it. ``spring``: what ``restoring="auto"`` would
    take on the record (:func:`_spring_of`); where no force follows the change there
    (``followed`` False), no force is advised, as none would answer: the warning says
    so instead."""
    if trend is None:
        return
    if trend.significant:
        like = (
            "; if the spring stiffens or softens with the swing (a cubic, Duffing spring), "
            "--restoring duffing (sidecar 'restoring': 'duffing') measures its β from the "
            "half periods and the energy lost per cycle with its potential; --restoring "
            "auto chooses the force from the half periods"
        )
        if drag and restoring is None and not chosen:
            like = (
                "; the law also misfits the decay, and a drag that grows with the swing "
                "shortens the half period as the swing decays by as much: fit with "
                "law='auto' (--law auto) first, which compares the laws and takes a law's "
                "own change off; if the change stays beyond the law it keeps, the spring "
                "stiffens or softens: --restoring duffing (sidecar 'restoring': 'duffing') "
                "measures its β from the half periods"
            )
        if spring is not None and not spring.followed and not drag:
            like = (
                "; no registered restoring force follows the change ("
                + ", ".join(
                    f"the {'Duffing spring' if force == 'duffing' else force}'s half "
                    f"periods leave {100 * left.change:+.3g} %"
                    for force, left in spring.left.items()
                    if force != "linear" and left is not None
                )
                + "): it is none of theirs (a frequency that drifts in time, a change "
                "that is not monotonic in the swing, a spring that stiffens or softens "
                "otherwise than as the cube of the swing), so naming a registered restoring "
                "force does not answer it, and the nuisance carries it"
            )
        if chosen and restoring is None:
            like = " (on the linear spring that --restoring auto took)"
        elif restoring is not None:
            like = (
                f" (on the {restoring.name}'s restoring force, which the law's model "
                "takes: the change is the part its half periods do not make)"
            )
        elif pendulum is not None:
            se = abs(trend.change / trend.z)
            if abs(trend.change - pendulum) <= max(3.0 * se, 0.25 * abs(pendulum)):
                like = (
                    f"; it changes as a pendulum's does over these swings ({100 * pendulum:+.3f} "
                    "%): for a pendulum, --restoring pendulum (sidecar 'restoring': "
                    "'pendulum') measures the energy lost per cycle with its potential "
                    "(--restoring auto chooses it from the half periods)"
                )
        if arm is not None:
            like = f"; {arm_advice(arm)}"
        warn(
            f"the oscillation's half period changes by {100 * trend.change:+.3f} % from the "
            f"largest swing to the smallest of {name or 'the run'} ({trend.z:+.0f} "
            f"standard errors) beyond what the law {law} makes: a stiffness that depends "
            "on amplitude, or a dissipation that changes the period otherwise than the law "
            "does; the constant Ω of the fit is then an average, and the reported "
            "parameters and ΔE(A) carry a frequency nuisance of "
            f"± {100 * frequency_nuisance_sd(trend):.2g} % for it{like}",
            # a law of constant half period on the linear spring: a misfit (exit 1), and
            # the nuisance that holds it leaves the intervals wide for the record
            LinearSpringWarning if restoring is None and constant_period else FrequencyTrendWarning,
        )


#: The growth of a length's noise read as a pendulum's angle, 1/cos θ at the largest
#: angle, beyond which the law's intervals are said to be uncalibrated
#: (:class:`~bayestribo.errors.ArmNoiseWarning`) and a misfit the noise's (1.5: 48°;
#: ``benchmarks/pendulum_arm.py``: at 20° and 40° 20 of 20 ζ intervals covered with no
#: misfit, at 60° 4 of 10 missed).
ARM_NOISE_GROWTH = 1.5


def _arm_noise_growth(run: Run) -> tuple[float, float] | None:
    """A length read as a pendulum's angle (:mod:`bayestribo.io.pendulum_arm`): its
    largest angle [°] and 1/cos of it, when that is beyond :data:`ARM_NOISE_GROWTH`."""
    arm = dict(run.metadata).get("pendulum_arm")
    if not arm:
        return None
    degrees = float(arm["largest_angle_deg"])
    grown = 1.0 / math.cos(math.radians(degrees))
    return (degrees, grown) if grown > ARM_NOISE_GROWTH else None


def _high_corner(prepared: Any) -> float | None:
    """The declared high-pass's corner over the oscillation's frequency, where it is
    beyond :data:`~bayestribo.signal.high_pass.CALIBRATED_CORNER`; None otherwise."""
    undone = dict(prepared.run.metadata).get("high_pass_undone")
    frequency = prepared.decay.natural_frequency_Hz
    if not undone or not frequency or not math.isfinite(frequency):
        return None
    ratio = float(undone["cutoff_Hz"]) / float(frequency)
    return ratio if ratio > CALIBRATED_CORNER else None


def _high_pass_sign(prepared: Any) -> HighPassSign | None:
    """A sensor high-pass's sign in the run as recorded (:func:`~bayestribo.signal.
    high_pass.detect_high_pass`, read from the velocity where it is recorded, else the
    displacement), for a run that declares none; None otherwise."""
    run, decay = prepared.run, prepared.decay
    meta = dict(run.metadata)
    if decay.turning_times is None or meta.get("sensor_high_pass") is not None:
        return None
    velocity = run.velocity is not None
    signal = run.velocity if velocity else run.displacement
    if signal is None:
        return None
    return detect_high_pass(run.time, signal, decay.turning_times, velocity=velocity)


def _simple_pendulum_arm(prepared: Any) -> float | None:
    """The length [m] of a simple pendulum recorded as a length whose half periods follow
    the record's change, for a run in metres not read as an angle; None otherwise."""
    run, decay = prepared.run, prepared.decay
    if run.length_unit != "m" or decay.turning_times is None:
        return None
    return simple_pendulum_arm(decay.turning_times, decay.peaks.value)


def _last_turns(decay: EnergyDecay) -> tuple[float, float | None]:
    """The record's last turning point (where its motion ends) and the one before it
    (None with one), about the equilibrium, in the sampled frame's unit of y."""
    y = np.asarray(decay.peaks.value, dtype=float) / decay.scaling.length_scale
    return float(y[-1]), (float(y[-2]) if y.size >= 2 else None)


def _spring_of(prepared: Any) -> RestoringChoice | None:
    """What ``restoring="auto"`` would take on the prepared run (its warnings silenced:
    read for the advice of the frequency warning only); None without turning times."""
    run, decay = prepared.run, prepared.decay
    if decay.turning_times is None:
        return None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return choose_restoring(
            decay.turning_times,
            decay.peaks.value / decay.scaling.length_scale,
            length_unit=run.length_unit,
            angle=decay.scaling.length_scale == 1.0,
            length_scale=decay.scaling.length_scale,
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


def _flagged(misfit: Misfit, shape: ShapeDeparture) -> bool:
    """True when :func:`_warn_misfit` has said the law misfits (or the discrepancy holds
    it)."""
    return bool(misfit[2] < MISFIT_P or shape.p_value < MISFIT_P)


def warn_shape(
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
    warn(text, MisfitWarning)


def _prior_spellings(option: str) -> str:
    """A ``--prior`` value (``mu_s_ratio=Uniform(1,40)``) as the fit's keyword and as the
    option: ``priors={'mu_s_ratio': Uniform(1,40)}, --prior mu_s_ratio=Uniform(1,40)``."""
    name, _, prior = option.partition("=")
    return f"priors={{{name!r}: {prior}}}, --prior {option}"


def _warn_misfit(
    name: str | None,
    misfit: Misfit,
    shape: ShapeDeparture,
    discrepancy: bool,
    law: str,
    compared: bool = False,
    half_cycles: int | None = None,
    arm: float | None = None,
    grown: tuple[float, float] | None = None,
    widen: Mapping[str, str] | None = None,
    prior_first: bool = True,
    stop: StopBeyondPrior | None = None,
    high_pass: HighPassSign | None = None,
    noise_note: str = "",
) -> None:
    """Say, with numbers, that the law misfits the run, and what to do (see
    :func:`summarise`); ``half_cycles``: how many the analysis holds (the law-free answer
    needs three, :func:`~bayestribo.inference.dissipation.turning_point_dissipation`);
    ``arm``: the length of a simple pendulum recorded as a length whose half periods
    follow the record's, the reading advised (no law holds on the wrong force);
    ``grown``: a length read as a pendulum's angle beyond :data:`ARM_NOISE_GROWTH`, its
    largest angle [°] and its noise's growth there, said instead of another law;
    ``widen``: parameters on a prior bound that is a belief, by name, with the
    ``--prior`` value that widens it
    (:func:`~bayestribo.inference.priors.widened_prior`), advised before another law (a
    law held below the sticking the record shows misfits it), the other advice after;
    ``prior_first``: the record stops and its misfit is the stop's (not
    :func:`misfit_of_the_law`), so the widened prior comes first; otherwise another law
    does, the prior after it; ``stop``: the record's stop needs a μ_s/μ_k beyond its
    prior (:func:`~bayestribo.inference.stop_prior.stop_beyond_prior`), said as the
    cause, and the prior that holds it advised first; ``high_pass``: a sensor
    high-pass's sign in the record (:func:`_high_pass_sign`), said with the option that
    undoes it before any other advice (no law holds on a high-passed record), and said
    alone where the law does not misfit; ``noise_note``: what the noise's colour at rest
    did (:func:`~bayestribo.signal.noise_colour.misfit_note`), said after the numbers."""
    if high_pass is not None:
        warn(
            f"{name or 'the run'}: {high_pass.advice()}; until then its parameters are not "
            "a measurement (the filter shifts the swing's centre and lowers the gain at the "
            "oscillation frequency, which biases every friction given as a length)",
            HighPassWarning,
        )
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
    # the noise's colour, where it is low-frequency, as a sentence after the numbers
    then = f".{noise_note}. So" if noise_note else ":"
    then_compared = f".{noise_note}. So" if noise_note else ";"
    if discrepancy:
        if not shaped:
            return  # white misfit only: the discrepancy's white term carries it
        warn(
            f"the law {law} is not adequate for {run}: {how}. The discrepancy terms "
            "carry the departure into the intervals, so its parameters are the law's best "
            "constant values over this decay, not those of a law that holds at every "
            "amplitude (bayestribo check shows how they change along the decay)",
            MisfitWarning,
        )
        return
    if compared:
        held = (
            ""
            if stop is None
            else f" {stop.describe()[0].upper()}{stop.describe()[1:]}: fit with the prior "
            f"widened ({_prior_spellings(stop.option)}), which may let a law hold."
        )
        warn(
            f"no law compared holds for {run}: the best, {law}, misfits it beyond its "
            f"noise ({how}){then_compared} its parameters are not a measurement of any "
            f"mechanism and its intervals are too narrow.{held} {law_free}",
            MisfitWarning,
        )
        return
    few = half_cycles is not None and half_cycles < FEWEST_HALF_CYCLES
    if high_pass is not None:
        return  # said above, with the option that answers it
    todo = (
        "Fit with law='auto' (--law auto): it compares the registered laws and keeps one that holds"
        if arm is None
        else arm_advice(arm)[0].upper() + arm_advice(arm)[1:]
    )
    if widen and not prior_first:
        names = ", ".join(widen)
        options = "; ".join(_prior_spellings(option) for option in widen.values())
        todo = (
            f"{todo}. {names} piles on its prior's upper bound too, a belief rather than a "
            "physical limit; the misfit departs smoothly along the decay, which a wider "
            "prior does not mend: if the law kept still piles on it, fit with the prior "
            f"widened ({options})"
        )
    elif widen:
        names = ", ".join(widen)
        options = "; ".join(_prior_spellings(option) for option in widen.values())
        cause = (
            f"{names} piles on its prior's upper bound, a belief rather than a physical "
            "limit: the record may ask for more (a pin that sticks harder), and a law held "
            "below it misfits"
            if stop is None
            else stop.describe()
        )
        todo = (
            f"{cause[0].upper()}{cause[1:]}. Fit with the prior widened ({options}); if the "
            f"law still misfits, {todo[0].lower()}{todo[1:]}"
        )
    if grown is not None:
        todo = (
            f"The run is a length read as a pendulum's angle (pendulum_radius_m), whose "
            f"noise grows as 1/cos θ, to {grown[1]:.2f}× its value at rest at the largest "
            f"angle ({grown[0]:.0f}°), where the fit takes it as at rest: at such angles "
            "that alone makes a misfit beyond the noise, whatever the law"
        )
    warn(
        f"the law {law} misfits {run} beyond its noise ({how}){then} its parameters are not "
        f"a measurement and its intervals are too narrow. {todo}"
        + (
            f". {law_free}"
            if few
            else "; the energy dissipated per cycle measured from the turning points "
            "(printed as 'turning points (law-free)') holds whatever the law"
        ),
        MisfitWarning,
    )
