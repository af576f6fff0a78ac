"""A law sampled in the frame of its own turning times: the prepare, start and sample
stages for one law.

:func:`sample_law` builds a law's posterior for a prepared run
(:func:`bayestribo.inference.build.build_posterior`) and samples it
(:func:`bayestribo.inference.chains.sample`). A law without a closed form is sampled
in its own frame: the run is prepared again (:func:`bayestribo.inference.preparation.
reframe`) at the frequency at which the law's turning times keep step with the
record's (:func:`~bayestribo.inference.preparation.law_frequency`), found from the
optimum in the record's frame. The fit of one law and the refit of the verdict of
``law="auto"`` (:mod:`bayestribo.inference.auto`) both go through here.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from bayestribo.inference.build import build_posterior
from bayestribo.inference.chains import sample_from
from bayestribo.inference.posterior import Posterior
from bayestribo.inference.preparation import law_frequency, reframe
from bayestribo.inference.priors import Prior
from bayestribo.inference.sampling import SamplerSettings
from bayestribo.inference.screening import LawOptimum
from bayestribo.inference.start import Start, find_start, maximum_a_posteriori, maximum_from
from bayestribo.inference.types import PreparedRun, Sampled
from bayestribo.model.laws import Law

__all__ = ["posterior_like", "sample_in_law_frame", "sample_law"]


def sample_law(
    prepared: PreparedRun,
    law: Law | None,
    *,
    model: str = "exact",
    discrepancy: bool = False,
    settings: SamplerSettings | None = None,
    seed: int | np.random.Generator | None = None,
    priors: Mapping[str, Prior] | None = None,
    fixed: Mapping[str, float] | None = None,
    progress: bool = False,
    weighted: int = 0,
) -> tuple[PreparedRun, Sampled]:
    """Build one law's posterior for a prepared run and sample it.

    A law without a closed form is sampled in its own frame: the run is prepared
    again at the frequency at which the law's turning times keep step with the
    record's, found from the optimum in the record's frame.

    Parameters
    ----------
    prepared : PreparedRun
        From :func:`bayestribo.inference.preparation.prepare`.
    law : Law or None
        The law (None: the default law of the run, with friction when it has contact).
    model, discrepancy, priors, fixed, progress
        As in :func:`bayestribo.fit`.
    settings : SamplerSettings, optional
        Sampler size; default :class:`~bayestribo.inference.sampling.SamplerSettings`.
    seed : int, Generator or None
        Seed of the sampler.
    weighted : int
        As in :func:`bayestribo.inference.chains.sample_from`: a surrogate's run that
        would be resampled by its importance weights is returned as it is where the
        weights of that many of its draws hold (0: never).

    Returns
    -------
    PreparedRun, Sampled
        The preparation sampled on (the law's frame) and the sampled posterior.
    """
    settings = settings or SamplerSettings()

    def posterior_on(prep: PreparedRun) -> Posterior:
        return build_posterior(
            prep.data,
            model=model,
            friction=prep.contact,
            discrepancy=discrepancy,
            priors=priors,
            fixed=fixed,
            law=law,
        )

    return sample_in_law_frame(prepared, posterior_on, settings, seed, progress, weighted=weighted)


def sample_in_law_frame(
    prepared: PreparedRun,
    posterior_on: Callable[[PreparedRun], Posterior],
    settings: SamplerSettings,
    seed: int | np.random.Generator | None,
    progress: bool = False,
    *,
    known: LawOptimum | None = None,
    known_run: Sampled | None = None,
    weighted: int = 0,
) -> tuple[PreparedRun, Sampled]:
    """Sample the posterior ``posterior_on(prepared)``; for a law without a closed
    form, in the law's frame, found from the optimum in the record's frame (one
    search from the first guesses, which no seed moves), the optimiser starting from
    that optimum in the law's frame.

    ``known`` and ``known_run``: the same law taken to its optimum on ``prepared``
    already, and sampled from there (the comparison of ``law="auto"``,
    :func:`bayestribo.inference.comparison.compare_prepared`). Where ``known`` was
    found on this very posterior (the same coordinates, and the same log density at
    its optimum to the bit), its optimum stands for the search (it is that search's
    optimum, or a nested law's start's where that is better: no seed moves either).
    Where the law's frame is then the record's own and the sampler would start
    where ``known_run`` started (the same second-pass optimum and Laplace covariance,
    to the bit), the posterior to sample is the one ``known_run`` sampled, and
    ``known_run`` is returned rather than that posterior sampled again.
    ``weighted``: as in :func:`bayestribo.inference.chains.sample_from`.
    """
    posterior = posterior_on(prepared)
    optimum = None
    framed = None
    if not posterior.law.closed_form:
        optimum = _known_search(posterior, known)
        if optimum is None:
            optimum = maximum_a_posteriori(posterior, prepared.decay)
        framed = _in_law_frame(prepared, posterior, optimum[0])
        if framed is not None:
            prepared = framed
            posterior = posterior_on(prepared)
            optimum = maximum_from(posterior, optimum[0], prepared.decay)
    start = find_start(posterior, prepared.decay, optimum=optimum)
    if framed is None and _same_start(start, known, known_run):
        return prepared, known_run
    sampled = sample_from(start, settings=settings, seed=seed, progress=progress, weighted=weighted)
    return prepared, sampled


def _known_search(
    posterior: Posterior, known: LawOptimum | None
) -> tuple[np.ndarray, np.ndarray, tuple[float, float] | None] | None:
    """``known``'s optimum when it was found on a posterior equal to ``posterior``
    (the same coordinates, the same log density at the optimum to the bit), else
    None."""
    if known is None or known.posterior.names != posterior.names:
        return None
    theta = np.asarray(known.optimum[0], dtype=float)[None]
    if not np.array_equal(known.posterior(theta), posterior(theta)):
        return None
    return known.optimum


def _same_start(start: Start, known: LawOptimum | None, known_run: Sampled | None) -> bool:
    """Whether the sampler would start where ``known_run`` started: the same law and
    coordinates, and the same second-pass optimum, Laplace covariance and log density
    there, to the bit."""
    if known is None or known_run is None or known_run.posterior is not known.second:
        return False
    theta, cov, _ = known.second_optimum
    if (
        start.posterior.names != known.second.names
        or start.posterior.law.name != known.second.law.name
    ):
        return False
    if not (np.array_equal(start.theta, theta) and np.array_equal(start.cov, cov)):
        return False
    point = np.asarray(theta, dtype=float)[None]
    return bool(np.array_equal(start.posterior(point), known.second(point)))


#: A law's frequency closer than this to the record's leaves the frame as it is.
_FRAME_TOLERANCE = 1e-9


def _in_law_frame(
    prepared: PreparedRun, posterior: Posterior, theta: np.ndarray
) -> PreparedRun | None:
    """The run prepared again in the frequency at which a nonlinear law's turning
    times keep step with the record's (:func:`bayestribo.inference.pipeline.
    law_frequency`), or None when that is the record's own frequency or is not found."""
    f = law_frequency(posterior, theta, prepared.decay)
    if f is None:
        return None
    f0 = prepared.decay.scaling.omega / (2.0 * np.pi)
    if abs(f / f0 - 1.0) <= _FRAME_TOLERANCE:
        return None
    return reframe(prepared, f)


def posterior_like(
    posterior: Posterior, prepared: PreparedRun, model: str, discrepancy: bool
) -> Posterior:
    """A posterior of the same law and fixed values on another preparation, with the
    default priors and every term of the law (as the comparison builds it: friction
    on a run without contact is fitted as a displacement, not dropped)."""
    return build_posterior(
        prepared.data,
        model=model,
        friction=True,
        discrepancy=discrepancy,
        fixed=dict(posterior.fixed) or None,
        law=posterior.law,
    )
