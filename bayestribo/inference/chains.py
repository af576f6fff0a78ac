"""The sample stage: a posterior, from its optimum, to converged chains.

:func:`sample_from` takes the start stage's :class:`~bayestribo.inference.start.Start`
(the posterior to sample and its optimum) and gives a
:class:`~bayestribo.inference.types.Sampled`: walkers about the optimum, and the sampler
(:func:`bayestribo.inference.sampling.run_ensembles`) run to convergence; for a law
without a closed form, on its quadratic surrogate where the exact posterior confirms
it (:mod:`bayestribo.inference.surrogate`). :func:`sample` is the start and sample
stages in a row, from a posterior.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.inference.correction import (
    CORRECTING_ATTEMPTS,
    MAX_CORRECTED_CV,
    MAX_WEIGHTED_CV,
    NEAR_CORRECTED_CV,
    evenly_spaced,
    exact_density,
    importance_corrected,
    weights_at,
)
from bayestribo.inference.identifiability import unidentified_reasons
from bayestribo.inference.missed import climbed, missed_reason
from bayestribo.inference.posterior import Posterior
from bayestribo.inference.reparameterised import Reparameterised, reparameterised
from bayestribo.inference.sampling import SamplerRun, SamplerSettings, run_ensembles
from bayestribo.inference.start import Start, find_start, initial_walkers
from bayestribo.inference.surrogate import (
    ATTEMPTS,
    NODE_SCALE,
    SurrogateCheck,
    check,
    regressed_posterior,
    surrogate_posterior,
)
from bayestribo.inference.types import DEFAULT_SETTINGS, Sampled
from bayestribo.signal.decay import EnergyDecay

__all__ = ["SAMPLER_FAILURES", "run_or_failure", "sample", "sample_from"]


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
    """The start and sample stages in a row: :func:`bayestribo.inference.start.
    find_start` (with ``optimum``, ``also_start_at`` and ``reweight``), then
    :func:`sample_from` (with ``settings``, ``seed``, ``progress`` and ``surrogate``).

    Returns
    -------
    Sampled
        Its ``posterior`` is the one sampled (the second pass's).
    """
    start = find_start(
        posterior, decay, optimum=optimum, also_start_at=also_start_at, reweight=reweight
    )
    return sample_from(start, settings=settings, seed=seed, progress=progress, surrogate=surrogate)


def sample_from(
    start: Start,
    *,
    settings: SamplerSettings = DEFAULT_SETTINGS,
    seed: int | np.random.Generator | None = None,
    progress: bool = False,
    surrogate: bool = True,
    weighted: int = 0,
) -> Sampled:
    """The sample stage: walkers about the start, and the sampler run to convergence.

    Parameters
    ----------
    start : Start
        From :func:`bayestribo.inference.start.find_start`.
    settings : SamplerSettings
        Walkers, ensembles, step ceiling and stopping rule.
    seed : int or Generator, optional
        Seed of the walkers and of the sampler's moves.
    progress : bool
        Show a progress bar.
    surrogate : bool
        For a law without a closed form, sample a quadratic surrogate of its Π and keep
        it where the exact posterior confirms it (:mod:`bayestribo.inference.surrogate`;
        the default); False: sample the exact posterior throughout.
    weighted : int
        A positive number n: a surrogate's run whose check failed is returned as it
        is where the weights of n of its draws evenly spaced are reliable for a caller
        that counts them by Kish's number (:func:`~bayestribo.inference.correction.
        weights_at` with :data:`~bayestribo.inference.correction.MAX_WEIGHTED_CV`),
        its check failed (``surrogate.passed`` False) and its surrogate posterior
        given, rather than another surrogate built or its draws resampled to the
        exact posterior (:func:`~bayestribo.inference.correction.
        importance_corrected`): for a caller that uses those draws alone and weights
        them (the halves' ΔE(A), :mod:`bayestribo.inference.halves`). 0 (the
        default): every draw resampled.

    Returns
    -------
    Sampled
        Of ``start.posterior``. An exact run sampled after failed surrogates is not
        converged where a point found from the surrogates' checked draws (climbed by the
        exact least squares) holds more density than all its draws
        (:mod:`bayestribo.inference.missed`).
    """
    rng = np.random.default_rng(seed)
    posterior, theta, cov, ratio_range = start.posterior, start.theta, start.cov, start.ratio_range
    checked: SurrogateCheck | None = None
    target: Posterior | None = None
    run: SamplerRun | None = None
    pointwise: NDArray | None = None
    first = None
    checked_best: list[NDArray] = []  # the best checked draw of each surrogate
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
        run, checked, target, pointwise = _sample_surrogate(
            posterior,
            theta,
            cov,
            walkers,
            settings,
            seed_of_run,
            progress,
            first,
            weighted,
            seen=checked_best,
        )
        if run is None:
            # the exact posterior is sampled: its walkers by its own density
            walkers = initial_walkers(
                posterior, theta, cov, ratio_range, settings.n_ensembles, settings.n_walkers, rng
            )
    if run is None:
        run = _exact_run(posterior, walkers, settings, seed_of_run, progress, rng)
        # the surrogates' checks evaluated the exact posterior elsewhere: a point there,
        # or the optimum climbed from the best of them, far above every draw is a part
        # of the posterior the walkers never reached
        points = climbed(posterior, checked_best) if checked_best else []
        missed = missed_reason(posterior, posterior.names, run.log_prob, points)
        if missed is not None:
            run = replace(run, converged=False, reasons=[*run.reasons, missed])
    # The optimiser can stop short of the optimum on the ridge of a law that misfits
    # (HarmOsc3 under viscous+coulomb+quadratic: χ² 228590 at its optimum, 8332 where
    # the walkers went); the best point the walkers visited then stands for the MAP
    # in the misfit checks.
    if run.log_prob.size and np.isfinite(run.log_prob).any():
        best = np.unravel_index(np.nanargmax(run.log_prob), run.log_prob.shape)
        point = np.array(run.chains[best], dtype=float)
        if posterior(point[None])[0] > posterior(theta[None])[0]:
            theta = point
    return Sampled(posterior, theta, run, settings, checked, target, pointwise)


def _exact_run(
    posterior: Posterior,
    walkers: NDArray,
    settings: SamplerSettings,
    seed: int,
    progress: bool,
    rng: np.random.Generator,
) -> SamplerRun:
    """The exact posterior sampled from ``walkers``: in its law's sampling coordinates
    where the law declares them (:mod:`bayestribo.inference.reparameterised`; the run
    mapped back to the law's own parameters), else in its own."""
    unseen = _unidentified(posterior)
    sampled: Posterior | Reparameterised | None = reparameterised(posterior)
    if sampled is None:
        sampled, start = posterior, walkers
    else:
        start = sampled.initial(walkers, rng)
        to_theta = sampled.to_theta
        law_unseen = unseen

        def unseen(draws: NDArray) -> list[str]:
            return law_unseen(to_theta(draws))

    # -- a failure inside sampling is a reported non-convergence (inference/modes.py) --
    run = run_or_failure(
        partial(run_ensembles, unidentified=unseen),
        sampled,
        start,
        settings,
        seed=seed,
        progress=progress,
    )
    # -- end of the failure guard --
    return run if sampled is posterior else sampled.law_run(run)


def _ridge_run(run: SamplerRun, checked: SurrogateCheck) -> SamplerRun:
    """A surrogate's run stopped on a ridge, its reasons saying that its draws are the
    surrogate's, its check failed and the exact posterior not sampled."""
    return replace(
        run,
        converged=False,
        reasons=[
            *run.reasons,
            "the draws are the quadratic surrogate's, whose check against the exact "
            f"posterior failed (importance weights' cv {checked.weight_cv:.3g}); the exact "
            "posterior, on the same ridge, was not sampled",
        ],
    )


def _unidentified(posterior: Posterior) -> Callable[[NDArray], list[str]]:
    """Why draws of ``posterior`` (or of its surrogate, in the same coordinates) show a
    ridge the record does not identify (a term at zero force, or no more increments
    than sampled parameters): a run stops once its rule cannot be met by the ceiling
    and the draws say why (:func:`~bayestribo.inference.identifiability.
    unidentified_reasons`), instead of walking the ridge to the ceiling. The posterior
    is read only when the rule asks (after a check the run cannot meet)."""

    def unseen(draws: NDArray) -> list[str]:
        n_increments = int(np.asarray(posterior.likelihood.data.increments).size) or None
        return unidentified_reasons(draws, posterior.names, posterior.law, n_increments)

    return unseen


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
    weighted: int = 0,
    seen: list[NDArray] | None = None,
) -> tuple[SamplerRun | None, SurrogateCheck | None, Posterior | None, NDArray | None]:
    """Sample the quadratic surrogate posterior of a law without a closed form and
    check it against the exact one (:mod:`bayestribo.inference.surrogate`).

    The surrogate is built about the maximum a posteriori with the Laplace scales
    (``first``, when the caller has built it already); if its check fails, fitted again
    by least squares to the exact Π at the failed surrogate's draws
    (:func:`~bayestribo.inference.surrogate.regressed_posterior`), or where those do
    not determine it, built again about the best draw checked with the surrogate
    posterior's spread (up to
    :data:`~bayestribo.inference.surrogate.ATTEMPTS` surrogates). A surrogate built
    again whose check fails by little (weights' cv at most
    :data:`~bayestribo.inference.correction.MAX_CORRECTED_CV`) has its draws resampled
    to the exact posterior by their importance weights where that is reliable
    (:func:`~bayestribo.inference.correction.importance_corrected`); once one has come
    near that reach (:data:`~bayestribo.inference.correction.NEAR_CORRECTED_CV`), up
    to :data:`~bayestribo.inference.correction.CORRECTING_ATTEMPTS` surrogates are built.
    Returns the run, the last check and the surrogate posterior when a check passed or a correction
    held (with the exact pointwise log-likelihood of the corrected draws, else None);
    ``(None, check, None, None)`` when none did (the caller samples the exact
    posterior). ``weighted``: a run whose check failed by no more than
    :data:`~bayestribo.inference.correction.MAX_WEIGHTED_CV` is returned as it is
    where the weights of that many of its draws hold by that limit, with its failed
    check and its surrogate posterior (:func:`sample_from`).
    """
    rng = np.random.default_rng(seed)
    sd = np.sqrt(np.clip(np.diag(np.atleast_2d(cov)), 0.0, None))
    centre, scale = theta, NODE_SCALE * sd
    checked: SurrogateCheck | None = None
    refit: Posterior | None = None
    attempts = ATTEMPTS
    attempt = 0
    while attempt < attempts:
        attempt += 1
        target = first if attempt == 1 and first is not None else refit
        if target is None:
            target = surrogate_posterior(posterior, centre, scale)
        if target is None or not target.uses_compiled:
            return None, checked, None, None
        run = run_or_failure(
            partial(run_ensembles, unidentified=_unidentified(posterior)),
            target,
            walkers,
            settings,
            seed=seed,
            progress=progress,
        )
        flat = run.chains.reshape(-1, run.chains.shape[-1])
        if flat.shape[0] < 2 or not np.all(np.isfinite(flat)):
            return None, checked, None, None
        # a run that did not converge is checked too, and kept when the check passes:
        # the fit reports its non-convergence as an exact run would, at a fraction of
        # the cost of sampling the exact posterior to the step ceiling
        checked = check(posterior, target, flat, rng, attempt=attempt)
        if seen is not None and checked.best is not None:
            seen.append(checked.best)
        if checked.passed:
            return run, checked, target, None
        if run.ridge:
            # stopped on a ridge the record does not identify: another surrogate, or
            # the exact posterior, walks the same ridge and stops unconverged too; the
            # law is reported not converged with this run's draws (not the exact
            # posterior's, and so said)
            return _ridge_run(run, checked), checked, target, None
        if attempt >= 2 and checked.weight_cv <= NEAR_CORRECTED_CV:
            # near the correction's reach: a refused correction or a check a little
            # beyond it is followed by further surrogates (up to CORRECTING_ATTEMPTS in
            # all) before the exact sampler
            attempts = max(attempts, CORRECTING_ATTEMPTS)
        if weighted and checked.weight_cv <= MAX_WEIGHTED_CV:
            # the caller weights the few draws it uses and counts them by Kish's
            # number: any surrogate whose weights there hold will do, the first one
            # included (HarmOsc2's second half under coulomb+power: cv 0.3-0.5 at the
            # first surrogate, then three or four more at 0.3 s each before one came
            # within the correction's reach)
            weights = weights_at(run, posterior, evenly_spaced(run, weighted), MAX_WEIGHTED_CV)
            if weights is not None:
                return run, replace(checked, weights=weights), target, None
        if attempt >= 2 and checked.weight_cv <= MAX_CORRECTED_CV:
            # a surrogate built again that still fails, by little: its draws resampled
            # to the exact posterior by their importance weights (inference/
            # correction.py; HarmOsc2's coulomb+power: cv 0.09 then 0.084, never 0.05).
            # The first one's failure is left to the next surrogate, which often
            # passes at less cost than the exact density at every draw
            corrected = importance_corrected(run, exact_density(posterior), rng, settings.rhat_max)
            if corrected is not None:
                record = SurrogateCheck(
                    corrected.draws,
                    corrected.weight_cv,
                    corrected.log_weight_sd,
                    attempt,
                    checked.best,
                    corrected=True,
                )
                return corrected.run, record, target, corrected.pointwise
        if checked.best is None:
            break
        refit = regressed_posterior(posterior, target, flat, rng)
        centre, scale = checked.best, NODE_SCALE * flat.std(axis=0)
    return None, checked, None, None


#: Errors inside the sampler that become a reported non-convergence (a NaN
#: log-probability is a :class:`~bayestribo.inference.sampling.NaNLogProbabilityError`,
#: itself a FloatingPointError; a NaN autocorrelation time turned into an integer is a
#: ValueError). Programming errors (TypeError, KeyError, ...) still propagate.
SAMPLER_FAILURES: tuple[type[BaseException], ...] = (ValueError, ArithmeticError)


def run_or_failure(
    run_ensembles: Callable[..., Any],
    log_prob: Callable[[NDArray], NDArray],
    initial: NDArray,
    settings: Any,
    *,
    seed: int | None,
    progress: bool = False,
) -> Any:
    """Run the sampler; a failure inside it becomes a run reported not converged.

    Parameters
    ----------
    run_ensembles : callable
        :func:`bayestribo.inference.sampling.run_ensembles`, or a stand-in with its
        signature.
    log_prob : callable
        Vectorised log posterior (with ``names``).
    initial : ndarray
        Starting walkers, shape (ensembles, walkers, params).
    settings : SamplerSettings
    seed : int or None
    progress : bool

    Returns
    -------
    SamplerRun
        The sampler's run; or, when it raised one of :data:`SAMPLER_FAILURES`, a run
        whose draws are the starting walkers (one per walker: a Gaussian
        approximation around the optimum, not a posterior), ``converged`` False and a
        reason naming the error.
    """
    try:
        return run_ensembles(log_prob, initial, settings, seed=seed, progress=progress)
    except SAMPLER_FAILURES as exc:
        initial = np.asarray(initial, dtype=float)
        n_ens, n_walkers, ndim = initial.shape
        names = tuple(getattr(log_prob, "names", ()))
        if len(names) != ndim:
            names = tuple(f"theta[{i}]" for i in range(ndim))
        with np.errstate(invalid="ignore"):
            lp = np.asarray(log_prob(initial.reshape(-1, ndim)), dtype=float)
        return SamplerRun(
            chains=initial.copy(),
            log_prob=lp.reshape(n_ens, n_walkers),
            autocorr_time=np.full(ndim, np.nan),
            n_steps=0,
            burn=0,
            thin=1,
            acceptance_fraction=float("nan"),
            ess=np.zeros(ndim),
            rhat=np.full(ndim, np.nan),
            converged=False,
            reasons=[
                f"the sampler failed ({type(exc).__name__}: {exc}); the draws are the "
                "starting walkers around the optimum, not a posterior"
            ],
            names=names,
        )
