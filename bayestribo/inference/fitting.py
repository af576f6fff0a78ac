"""The single-run Bayesian fit: recording → Π increments → posterior of ζ and μ_k.

:func:`fit` checks its specification (:class:`~bayestribo.inference.spec.FitSpec`) and
runs the stages in a row: prepare (:mod:`bayestribo.inference.preparation`), then for
one law build, start and sample (:func:`bayestribo.inference.law_frame.sample_law`),
check and summarise (:mod:`bayestribo.inference.checks`,
:mod:`bayestribo.inference.summarising`); for ``law="auto"``, compare, choose, refit
and check (:func:`bayestribo.inference.auto.fit_auto`).
"""

from __future__ import annotations

import dataclasses
import os
import time
from collections.abc import Callable, Mapping
from typing import Any, Literal

import numpy as np

from bayestribo import DEFAULT_SEED
from bayestribo.errors import BayestriboError
from bayestribo.inference.auto import fit_auto
from bayestribo.inference.boundary import boundary_mixture
from bayestribo.inference.checks import check
from bayestribo.inference.law_frame import sample_law
from bayestribo.inference.likelihood import MODELS
from bayestribo.inference.preparation import prepare
from bayestribo.inference.priors import Prior
from bayestribo.inference.result import FitResult
from bayestribo.inference.spec import FitSpec, spec_fields
from bayestribo.inference.summarising import summary
from bayestribo.io.options import ReadOptions
from bayestribo.io.run import Run
from bayestribo.model.laws import Law, get_law
from bayestribo.signal.channel_noise import reused_noise
from bayestribo.signal.noise import NoiseModel

__all__ = ["fit", "sample_law"]


def fit(
    run: Run | str | os.PathLike[str],
    *,
    spec: FitSpec | Mapping[str, Any] | None = None,
    model: str = "exact",
    seed: int | None = DEFAULT_SEED,
    n_walkers: int = 16,
    n_ensembles: int = 2,
    max_steps: int = 20_000,
    discrepancy: bool = False,
    priors: Mapping[str, Prior | Mapping[str, Any]] | None = None,
    fixed: Mapping[str, float] | None = None,
    grid_points: int | None = None,
    skip_oscillations: int = 1,
    progress: bool = False,
    read_options: ReadOptions | Mapping[str, Any] | None = None,
    noise: NoiseModel | None = None,
    correct_channels: bool = True,
    notch: float | Literal["auto"] | None = None,
    law: str | Law | None = None,
    law_progress: Callable[[str], None] | None = None,
    restoring: str | None = None,
) -> FitResult:
    """Posterior of ζ and μ_k (or ζ₀, or the friction displacement) for one run, or
    of the parameters of another dissipation law, with the energy dissipated per
    cycle ΔE(A).

    Parameters
    ----------
    run : Run or path
        The recording (:class:`bayestribo.io.run.Run`) or a file for
        :func:`bayestribo.read_run` (with ``read_options``).
    spec : FitSpec or mapping, optional
        The whole specification of the fit (:class:`~bayestribo.inference.spec.FitSpec`,
        or a mapping of its fields, :meth:`~bayestribo.inference.spec.FitSpec.to_dict`).
        The keywords below that are fields of it build one; given with ``spec``, a
        keyword that differs from its default replaces the spec's field. The result
        records the specification (``result.spec``).
    model : {"exact", "averaged"}
        Forward model of Π (the exact one by default; the averaged one is biased by
        about 2ζ² of Π, far more than the noise of a good record).
    seed : int or None
        Seed of everything random in the fit (walkers, moves, predictive draws);
        default :data:`bayestribo.DEFAULT_SEED`, so that a fit is reproducible and
        records its seed. None draws fresh entropy (recorded as -1).
    n_walkers, n_ensembles, max_steps : int
        Sampler size: walkers per ensemble, independent ensembles, step ceiling.
    discrepancy : bool
        Add the model-discrepancy terms (:mod:`bayestribo.inference.likelihood`): a
        white relative error on E and a relative departure of the increments smooth
        along the decay, each with its scale sampled (``log10_discrepancy``,
        ``log10_shape``).
    priors : mapping, optional
        Replacement priors by parameter name (see
        :func:`bayestribo.inference.priors.default_priors`): a
        :class:`~bayestribo.inference.priors.Prior`, or its plain data
        (``{"type": "Uniform", "low": 0, "high": 0.1}``).
    fixed : mapping, optional
        Parameters held at a value instead of sampled, e.g. ``{"zeta": 0.0}``.
    grid_points : int, optional
        Number of Π increments; default one per half cycle (see
        :mod:`bayestribo.signal.increments`).
    skip_oscillations : int
        Oscillations skipped after the release.
    progress : bool
        Show a progress bar.
    read_options : ReadOptions or mapping, optional
        How to read ``run`` when it is a path (:class:`~bayestribo.io.options.ReadOptions`,
        or a mapping of the options of :func:`bayestribo.read_run`).
    noise : NoiseModel, optional
        Use this noise model instead of the recording's.
    correct_channels : bool
        Correct the velocity channel to the displacement when their gain ratio or
        delay is off by more than the recording's own uncertainty
        (:func:`bayestribo.inference.calibration.calibrate_channels`); the result's
        ``channel_calibration`` records what was measured and done.
    notch : float, "auto" or None
        Mains line to subtract, measured at rest (:func:`bayestribo.inference.prepare`).
    law : str or Law, optional
        The dissipation law: terms of :mod:`bayestribo.model.laws` joined with ``+``
        (``"viscous+coulomb"``, the default; ``"viscous+quadratic"``,
        ``"coulomb+hysteretic"``, ...) or a :class:`~bayestribo.model.laws.Law`. A run
        without contact (``load_N`` of 0) drops the law's friction terms. A law of
        several terms is averaged over its boundaries: where the absence of one of its
        terms (no friction, no viscous damping, no quadratic drag, ...) is probable (at
        least 1 %, from the Savage–Dickey density ratio), the law without that term is
        fitted too and makes that share of the draws, at most half
        (:mod:`bayestribo.inference.boundary`; the result's ``boundary`` says what was
        done). ``"auto"`` is not averaged (its comparison holds the nested laws
        already); it compares the laws the registry's terms make by the rule of
        :mod:`bayestribo.model.laws.candidates`
        (:func:`bayestribo.inference.comparison.auto_laws`): each is taken to its
        optimum, those too far behind the best there to win are screened out, the rest
        sampled, and the simplest adequate one as good as the best by PSIS-LOO is kept
        (:mod:`bayestribo.inference.comparison`; the result's ``law_comparison`` says
        which and why); when none of them is adequate, the law-free ``"free"`` law
        (ΔE(A) any increasing polynomial of degree 1-4) is fitted too. The result is
        the chosen law's fit with every one of its terms (on a run with contact, what
        ``law=<its name>`` gives, from the comparison's optimum: for a law of several
        terms, the best reached from its nested laws' optima, which agrees with the
        first guesses' to the least squares' tolerance or is higher); a law without a
        closed form is fitted again in its own frame, from that optimum.
    law_progress : callable, optional
        With ``law="auto"``: called with one line of text per law as the comparison
        goes (its optimum; then its sampling, or why it is not sampled).
    restoring : str, optional
        The oscillator's restoring force (:mod:`bayestribo.model.restoring`:
        ``"linear"``, ``"pendulum"``, ``"duffing"``), over the run's sidecar
        ``restoring``; default the sidecar's, else linear. ``"auto"`` chooses it from
        how the half period changes with the swing, measured from the turning times
        (:mod:`bayestribo.inference.restoring_choice`): constant within its noise,
        linear (the fit is then the linear one's, unchanged); a run in radians whose
        change is the pendulum's own, pendulum; otherwise duffing, β measured. When
        no force follows the change the one that leaves the least of it is kept, with
        a :class:`~bayestribo.errors.FrequencyTrendWarning`. The result's
        ``restoring["auto"]`` records the choice and why.

    Returns
    -------
    FitResult
        A run that did not converge is returned with ``converged`` False and a
        :class:`~bayestribo.errors.ConvergenceWarning` is raised as a warning.

    Examples
    --------
    >>> import bayestribo
    >>> result = bayestribo.fit("data/runs/glycerol-N0.31-r1.csv", seed=1)  # doctest: +SKIP
    >>> result.summary(prob=0.9)["mu_k"].interval  # doctest: +SKIP
    """
    start = time.perf_counter()
    keywords = {
        "model": model,
        "seed": seed,
        "n_walkers": n_walkers,
        "n_ensembles": n_ensembles,
        "max_steps": max_steps,
        "discrepancy": discrepancy,
        "priors": priors,
        "fixed": fixed,
        "grid_points": grid_points,
        "skip_oscillations": skip_oscillations,
        "read_options": read_options,
        "correct_channels": correct_channels,
        "notch": notch,
        "law": law,
        "restoring": restoring,
    }
    # checked before the run is read and prepared, each error naming its field
    spec = FitSpec.of(spec, **{k: v for k, v in keywords.items() if v != _KEYWORD_DEFAULTS[k]})
    if spec.model not in MODELS:
        raise BayestriboError(f"model: expected one of {MODELS}, got {spec.model!r}")
    model, seed, discrepancy = spec.model, spec.seed, spec.discrepancy
    auto = spec.law == "auto"
    the_law = None if auto else get_law(law if isinstance(law, Law) else spec.law)
    priors = {k: Prior.from_spec(v) for k, v in spec.priors.items()} or None
    fixed = dict(spec.fixed) or None
    settings = spec.sampler_settings()
    rng = np.random.default_rng(seed)
    reading = spec.reading()
    if isinstance(run, Run) and spec.restoring is not None:
        # a run already read takes the restoring force in its metadata
        run, reading = run.with_metadata(restoring=spec.restoring), spec.read_options
    # the first pass and every second pass (each law's of law="auto", each boundary
    # law's of the default law) take the recorded channel's Monte Carlo noise, and its
    # derivative, made once (bayestribo.signal.channel_noise): the same numbers
    with reused_noise():
        prepared = prepare(
            run,
            skip_oscillations=spec.skip_oscillations,
            grid_points=spec.grid_points,
            noise=noise,
            read_options=reading,
            correct_channels=spec.correct_channels,
            notch=spec.notch_Hz,
        )
        if auto:
            summarised = fit_auto(
                prepared,
                rng,
                model=model,
                discrepancy=discrepancy,
                settings=settings,
                recorded_seed=seed,
                progress=law_progress,
            )
        else:
            prepared, sampled = sample_law(
                prepared,
                the_law,
                model=model,
                discrepancy=discrepancy,
                settings=settings,
                seed=rng,
                priors=priors,
                fixed=fixed,
                progress=progress,
            )
            checks = check(prepared, sampled)
            sampled, boundary = boundary_mixture(
                checks.sampled,
                lambda nested: sample_law(
                    prepared,
                    get_law(nested),
                    model=model,
                    discrepancy=discrepancy,
                    settings=settings,
                    seed=rng.spawn(1)[0],
                    priors=_nested(priors, nested),
                    fixed=_nested(fixed, nested),
                )[1],
                lambda: rng.spawn(1)[0],
            )
            checks = dataclasses.replace(checks, sampled=sampled)
            summarised = summary(prepared, sampled, seed=rng, recorded_seed=seed, checks=checks)
            if boundary is not None:
                summarised = dataclasses.replace(
                    summarised, record=summarised.record.replace(boundary=boundary)
                )
    record = summarised.record.replace(spec=spec.to_dict(), seconds=time.perf_counter() - start)
    return dataclasses.replace(summarised, record=record).result()


def _nested(given: Mapping[str, Any] | None, nested: str) -> dict[str, Any] | None:
    """The priors (or fixed values) given for the law that its nested law ``nested``
    has (:mod:`bayestribo.inference.boundary`)."""
    names = {p.name for p in get_law(nested).parameters}
    names |= {"y0", "log10_discrepancy", "log10_shape"}
    return {k: v for k, v in (given or {}).items() if k in names} or None


#: The defaults of :func:`fit`'s keywords that are fields of :class:`FitSpec` (None for
#: the mappings and reading options: the spec's empty ones).
_KEYWORD_DEFAULTS: dict[str, Any] = {
    **{f.metadata["keyword"] or f.name: f.default for f in spec_fields()},
    "priors": None,
    "fixed": None,
    "read_options": None,
}
