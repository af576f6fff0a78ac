"""The single-run Bayesian fit: recording → Π increments → posterior of ζ and μ_k.

:func:`fit` is the four steps of :mod:`bayestribo.inference.pipeline` in a row:
prepare the data, build the posterior, sample, summarise.
"""

from __future__ import annotations

import json
import os
import time
import warnings
from collections.abc import Callable, Mapping
from typing import Any, Literal

import numpy as np

from bayestribo import DEFAULT_SEED
from bayestribo.errors import BayestriboError, MisfitWarning
from bayestribo.inference.likelihood import MODELS
from bayestribo.inference.pipeline import (
    PreparedRun,
    build_posterior,
    law_frequency,
    prepare,
    reframe,
    sample,
    summarise,
)
from bayestribo.inference.priors import Prior
from bayestribo.inference.result import FitResult, plain_data
from bayestribo.inference.sampling import SamplerSettings
from bayestribo.inference.spec import FitSpec, spec_fields
from bayestribo.inference.start import maximum_a_posteriori, maximum_from
from bayestribo.io.options import ReadOptions
from bayestribo.io.run import Run
from bayestribo.model.laws import Law, get_law
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
        without contact (``load_N`` of 0) drops the law's friction terms. ``"auto"``
        compares the laws the registry's terms make by the rule of
        :mod:`bayestribo.model.laws.candidates`
        (:func:`bayestribo.inference.comparison.auto_laws`): each is taken to its
        optimum, those too far behind the best there to win are screened out, the rest
        sampled, and the simplest adequate one as good as the best by PSIS-LOO is kept
        (:mod:`bayestribo.inference.comparison`; the result's ``law_comparison`` says
        which and why); when none of them is adequate, the law-free ``"free"`` law
        (ΔE(A) any increasing polynomial of degree 1-4) is fitted too. The result is
        the chosen law's fit with every one of its terms (on a run with contact, what
        ``law=<its name>`` gives); a law without a closed form is fitted again in its
        own frame, from the optimiser's optimum.
    law_progress : callable, optional
        With ``law="auto"``: called with one line of text per law as the comparison
        goes (its optimum; then its sampling, or why it is not sampled).

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
    prepared = prepare(
        run,
        skip_oscillations=spec.skip_oscillations,
        grid_points=spec.grid_points,
        noise=noise,
        read_options=spec.reading(),
        correct_channels=spec.correct_channels,
        notch=spec.notch_Hz,
    )
    comparison = None
    if auto:
        from bayestribo.inference.comparison import auto_laws, compare_prepared

        comparison, runs = compare_prepared(
            prepared,
            auto_laws(),
            seed=int(rng.integers(2**31)),
            model=model,
            settings=settings,
            discrepancy=discrepancy,
            law_free=True,
            progress=law_progress,
        )
        common = prepared
        sampled = runs[comparison.verdict]
        if not sampled.posterior.law.closed_form:
            # the verdict fitted again as that law alone is (sample_law): in the frame
            # of its own turning times, found from the optimiser's optimum. The
            # comparison's best draw, which the seed moves, set the frame before, and
            # the frame moved the answer by up to 0.7 posterior sd from seed to seed
            verdict = sampled.posterior
            prepared, sampled = _sample_in_law_frame(
                prepared,
                lambda prep: _posterior_like(verdict, prep, model, discrepancy),
                settings,
                rng,
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
    result = summarise(
        prepared, sampled, seed=rng, recorded_seed=seed, compared=comparison is not None
    )
    if comparison is not None:
        result.attrs["law_comparison_json"] = json.dumps(plain_data(comparison.to_dict()))
        averaged = _averaged_band(common, runs, comparison, result, (prepared, sampled))
        if averaged is not None:
            attrs = result.attrs
            attrs["verdict_dissipation_json"] = attrs["dissipation_json"]
            attrs["dissipation_json"] = json.dumps(plain_data(averaged))
        comparison = _check_halves(comparison, common, rng, settings, model, discrepancy)
        record = comparison.to_dict()
        screened = {
            law: row["map"]
            for law, row in record["table"].items()
            if row.get("screened") and row.get("map")
        }
        record["departures"] = _law_departures(
            common, runs, result, screened, model=model, discrepancy=discrepancy
        )
        result.attrs["law_comparison_json"] = json.dumps(plain_data(record))
    result.attrs["spec_json"] = spec.to_json()
    result.attrs["seconds"] = time.perf_counter() - start
    return result


#: The defaults of :func:`fit`'s keywords that are fields of :class:`FitSpec` (None for
#: the mappings and reading options: the spec's empty ones).
_KEYWORD_DEFAULTS: dict[str, Any] = {
    **{f.metadata["keyword"] or f.name: f.default for f in spec_fields() if f.name != "restoring"},
    "priors": None,
    "fixed": None,
    "read_options": None,
}


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
) -> tuple[PreparedRun, Any]:
    """Steps 2 and 3 of :func:`fit` for one law: build its posterior and sample it.

    A law without a closed form is sampled in its own frame: the run is prepared
    again at the frequency at which the law's turning times keep step with the
    record's, found from the optimum in the record's frame.

    Parameters
    ----------
    prepared : PreparedRun
        From :func:`bayestribo.inference.pipeline.prepare`.
    law : Law or None
        The law (None: the default law of the run, with friction when it has contact).
    model, discrepancy, priors, fixed, progress
        As in :func:`fit`.
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

    def posterior_on(prep: PreparedRun) -> Any:
        return build_posterior(
            prep.data,
            model=model,
            friction=prep.contact,
            discrepancy=discrepancy,
            priors=priors,
            fixed=fixed,
            law=law,
        )

    return _sample_in_law_frame(prepared, posterior_on, settings, seed, progress)


def _sample_in_law_frame(
    prepared: PreparedRun,
    posterior_on: Callable[[PreparedRun], Any],
    settings: SamplerSettings,
    seed: int | np.random.Generator | None,
    progress: bool = False,
) -> tuple[PreparedRun, Any]:
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
    sampled = sample(
        posterior,
        prepared.decay,
        settings=settings,
        seed=seed,
        progress=progress,
        optimum=optimum,
    )
    return prepared, sampled


def _check_halves(
    comparison: Any,
    prepared: PreparedRun,
    rng: np.random.Generator,
    settings: SamplerSettings,
    model: str,
    discrepancy: bool,
) -> Any:
    """The verdict of an adequate comparison fitted to each half of the motion
    (:func:`bayestribo.inference.halves.law_halves`); when they disagree the comparison
    is no longer adequate, and a :class:`~bayestribo.errors.MisfitWarning` says so."""
    from dataclasses import replace

    from bayestribo.inference.halves import law_halves

    if not comparison.adequate or get_law(comparison.verdict).name == get_law("free").name:
        return comparison
    halves = law_halves(
        prepared,
        comparison.verdict,
        seed=int(rng.integers(2**31)),
        settings=settings,
        model=model,
        discrepancy=discrepancy,
    )
    if halves.agree:
        return replace(comparison, halves=halves.to_dict())
    checked = replace(comparison, adequate=False, halves=halves.to_dict())
    warnings.warn(
        f"{prepared.name or 'the run'}: {checked.describe()}. {halves.describe()} "
        "(result.law_comparison['halves'])",
        MisfitWarning,
        stacklevel=3,
    )
    return checked


#: Draws of each compared law from which its ΔE(A) is set beside the turning points'.
_DEPARTURE_DRAWS = 200


def _law_departures(
    common: PreparedRun,
    runs: Mapping[str, Any],
    result: FitResult,
    optima: Mapping[str, Mapping[str, float]] | None = None,
    *,
    model: str = "exact",
    discrepancy: bool = False,
) -> dict[str, Any]:
    """How close each compared law's ΔE(A) comes to the turning points' (the law-free
    answer), by law: :func:`~bayestribo.inference.dissipation.shape_agreement` of its
    posterior mean at the result's swings, from :data:`_DEPARTURE_DRAWS` draws of the
    comparison's fit on the common preparation; for a law screened out at its optimum
    (``optima``: its values there by name), of its ΔE(A) at that optimum. Empty
    without a turning-point answer."""
    import dataclasses

    from bayestribo.inference.dissipation import (
        dissipation_band,
        physical_scale,
        shape_agreement,
    )

    measured = result.turning_point_dissipation
    band = result.dissipation
    if not measured or not band or not band.get("amplitude"):
        return {}
    sensor = result._attr("sensor_json", None) or {}
    scale = physical_scale(common.decay.scaling, common.metadata)
    scale = dataclasses.replace(
        scale, length_scale=scale.length_scale / float(sensor.get("gain", 1.0))
    )
    swings = np.asarray(band["amplitude"], dtype=float) / scale.length_scale
    out: dict[str, Any] = {}
    for law, sampled in runs.items():
        flat = sampled.run.chains.reshape(-1, sampled.run.chains.shape[-1])
        pick = flat[np.linspace(0, flat.shape[0] - 1, _DEPARTURE_DRAWS).astype(int)]
        try:
            own = dissipation_band(sampled.posterior, pick, swings, scale)
            out[law] = shape_agreement(own, measured)
        except ValueError:
            continue
    for law, values in (optima or {}).items():
        posterior = build_posterior(
            common.data, model=model, friction=True, discrepancy=discrepancy, law=get_law(law)
        )
        try:
            point = np.array([[values[n] for n in posterior.names]], dtype=float)
            own = dissipation_band(posterior, point, swings, scale)
            out[law] = shape_agreement(own, measured)
        except (KeyError, ValueError):
            continue
    return out


def _averaged_band(
    common: PreparedRun,
    runs: Mapping[str, Any],
    comparison: Any,
    result: FitResult,
    final: tuple[PreparedRun, Any],
) -> dict[str, Any] | None:
    """ΔE(A) averaged over the adequate, converged laws as good as the verdict
    (:func:`bayestribo.inference.dissipation.averaged_dissipation`); None when the
    verdict stands alone.

    The verdict enters with its final posterior (in its own frame, ``final``), the
    others with the comparison's, on the common preparation. A law without a closed
    form whose turning times ask for another frame than the common one by more than a
    quarter of the band's relative sd (a nonlinear drag, whose frame the decrement
    misjudges by up to 1e-4, two standard deviations of ΔE at ten times the
    resolution) is left out of the average rather than let in biased, and named in
    ``left_out``."""
    from bayestribo.inference.dissipation import averaged_dissipation, physical_scale
    from bayestribo.inference.pipeline import law_frequency

    if not comparison.adequate:
        return None
    band = result.dissipation
    if not band:
        return None
    common_scale = physical_scale(common.decay.scaling, common.metadata)
    f0 = common.decay.scaling.omega / (2.0 * np.pi)
    # a frame error ε moves ΔE(A) by about ε relative: a quarter of the band's sd
    mean, sd = np.asarray(band["mean"], dtype=float), np.asarray(band["sd"], dtype=float)
    limit = 0.25 * float(np.median(np.abs(sd / mean)))
    members, left_out = [], []
    for law in comparison.as_good:
        row = comparison.table.get(law, {})
        if law not in runs or not (row.get("adequate") and row.get("converged")):
            continue
        if law == comparison.verdict:
            prepared, sampled = final
            scale = physical_scale(prepared.decay.scaling, prepared.metadata)
        else:
            sampled, scale = runs[law], common_scale
            if not sampled.posterior.law.closed_form:
                f = law_frequency(sampled.posterior, sampled.theta_map, common.decay)
                if f is None or abs(f / f0 - 1.0) > limit:
                    left_out.append(law)
                    continue
        chains = sampled.run.chains
        members.append((law, sampled.posterior, chains.reshape(-1, chains.shape[-1]), scale))
    if len(members) < 2:
        return None
    frequency_sd = float(result.attrs.get("frequency_nuisance_sd", 0.0))
    try:
        out = averaged_dissipation(
            members,
            np.asarray(band["amplitude"], dtype=float),
            prob=float(band["prob"]),
            frequency_sd=frequency_sd,
        )
    except ValueError:
        return None
    out["left_out"] = left_out
    return out


#: A law's frequency closer than this to the record's leaves the frame as it is.
_FRAME_TOLERANCE = 1e-9


def _in_law_frame(prepared: PreparedRun, posterior: Any, theta: Any) -> PreparedRun | None:
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


def _posterior_like(posterior: Any, prepared: PreparedRun, model: str, discrepancy: bool) -> Any:
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
