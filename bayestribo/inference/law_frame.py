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
from bayestribo.inference.start import find_start, maximum_a_posteriori, maximum_from
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

    return sample_in_law_frame(prepared, posterior_on, settings, seed, progress)


def sample_in_law_frame(
    prepared: PreparedRun,
    posterior_on: Callable[[PreparedRun], Posterior],
    settings: SamplerSettings,
    seed: int | np.random.Generator | None,
    progress: bool = False,
) -> tuple[PreparedRun, Sampled]:
    """Sample the posterior ``posterior_on(prepared)``; for a law without a closed
    form, in the law's frame, found from the optimum in the record's frame (one
    search from the first guesses, which no seed moves), the optimiser starting from
    that optimum in the law's frame."""
    posterior = posterior_on(prepared)
    optimum = None
    if not posterior.law.closed_form:
        optimum = maximum_a_posteriori(posterior, prepared.decay)
        framed = _in_law_frame(prepared, posterior, optimum[0])
        if framed is not None:
            prepared = framed
            posterior = posterior_on(prepared)
            optimum = maximum_from(posterior, optimum[0], prepared.decay)
    start = find_start(posterior, prepared.decay, optimum=optimum)
    sampled = sample_from(start, settings=settings, seed=seed, progress=progress)
    return prepared, sampled


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
