"""``law="auto"``: compare the laws, choose one, fit it again, and check it.

:func:`fit_auto` takes a prepared run (:func:`bayestribo.inference.preparation.prepare`)
and gives the :class:`~bayestribo.inference.summarising.Summary` of the law it chooses
(its record complete before the result is made):

1. compare: every candidate law taken to its optimum, screened, sampled and compared
   by PSIS-LOO (:func:`bayestribo.inference.comparison.compare_prepared`), giving a
   :class:`~bayestribo.inference.records.LawComparison` and each law's
   :class:`~bayestribo.inference.types.Sampled`;
2. choose: the comparison's verdict; a law without a closed form refitted alone in
   the frame of its own turning times (:func:`bayestribo.inference.law_frame.
   sample_in_law_frame`, from the comparison's optimum; where that frame is the
   record's own, the posterior it samples is the comparison's, whose draws are kept),
   and summarised (:func:`bayestribo.inference.summarising.summarise`);
3. check: ΔE(A) averaged over the laws as good as the verdict (:func:`_averaged_band`),
   the verdict fitted to each half of the motion (:func:`bayestribo.inference.halves.
   law_halves`) and each law's ΔE(A) set beside the turning points' (
   :func:`_law_departures`), all recorded in the fit's record.

This module imports the stages; no stage imports it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from bayestribo._warnings import warn
from bayestribo.errors import MisfitWarning, ShapeUnresolvedWarning
from bayestribo.inference.build import build_posterior
from bayestribo.inference.comparison import auto_laws, compare_prepared
from bayestribo.inference.dissipation import (
    SHAPE_SLOPE_TOLERANCE,
    averaged_dissipation,
    dissipation_band,
    physical_scale,
    shape_agreement,
)
from bayestribo.inference.fit_record import FitRecord, plain_data
from bayestribo.inference.halves import law_halves
from bayestribo.inference.law_frame import posterior_like, sample_in_law_frame
from bayestribo.inference.preparation import law_frequency
from bayestribo.inference.records import LawComparison
from bayestribo.inference.sampling import SamplerSettings
from bayestribo.inference.screening import LawOptimum
from bayestribo.inference.summarising import Summary, summary
from bayestribo.inference.types import PreparedRun, Sampled
from bayestribo.model.laws import get_law

__all__ = ["fit_auto", "shape_unresolved"]


def fit_auto(
    prepared: PreparedRun,
    rng: np.random.Generator,
    *,
    model: str,
    discrepancy: bool,
    settings: SamplerSettings,
    recorded_seed: int | None,
    progress: Callable[[str], None] | None = None,
) -> Summary:
    """The fit of ``law="auto"`` on a prepared run (module notes).

    Parameters
    ----------
    prepared : PreparedRun
        From :func:`bayestribo.inference.preparation.prepare`.
    rng : Generator
        The fit's random stream (the comparison's seed, the refit, the summary's draws
        and the halves' seed are drawn from it in that order).
    model, discrepancy : str, bool
        As in :func:`bayestribo.fit`.
    settings : SamplerSettings
        Sampler size of every law's fit.
    recorded_seed : int or None
        The fit's seed, recorded in the result.
    progress : callable, optional
        Called with one line of text per law as the comparison goes, and one as each
        later stage that fits the verdict again starts (its frame, its halves).

    Returns
    -------
    Summary
        The chosen law's fit (:meth:`~bayestribo.inference.summarising.Summary.result`
        makes the result), its record's ``law_comparison`` the comparison with the
        halves' check and each law's departure from the turning points' ΔE(A), its
        ``dissipation`` averaged over the laws as good where there are several.
    """
    at_optima: dict[str, LawOptimum] = {}
    comparison, runs = compare_prepared(
        prepared,
        auto_laws(),
        seed=int(rng.integers(2**31)),
        model=model,
        settings=settings,
        discrepancy=discrepancy,
        law_free=True,
        progress=progress,
        at_optima=at_optima,
    )
    common = prepared
    sampled = runs[comparison.verdict]
    if not sampled.posterior.law.closed_form:
        # the verdict fitted again as that law alone is (sample_law): in the frame
        # of its own turning times, found from the optimiser's optimum. The
        # comparison's best draw, which the seed moves, set the frame before, and
        # the frame moved the answer by up to 0.7 posterior sd from seed to seed. The
        # comparison's search from the first guesses is the record frame's; where the
        # law's frame is the record's own, the comparison's draws are those of the
        # very posterior the refit would sample, and are kept
        verdict = sampled.posterior
        (progress or (lambda text: None))(
            f"fitting {comparison.verdict} again in the frame of its own turning times"
        )
        prepared, sampled = sample_in_law_frame(
            prepared,
            lambda prep: posterior_like(verdict, prep, model, discrepancy),
            settings,
            rng,
            known=at_optima.get(comparison.verdict),
            known_run=sampled,
        )
    summarised = summary(prepared, sampled, seed=rng, recorded_seed=recorded_seed, compared=True)
    record = summarised.record
    averaged = _averaged_band(common, runs, comparison, record, (prepared, sampled))
    if averaged is not None:
        record = record.replace(
            verdict_dissipation=record.dissipation, dissipation=plain_data(averaged)
        )
    comparison = _check_halves(comparison, common, rng, settings, model, discrepancy, progress)
    compared = comparison.to_dict()
    screened = {
        law: row["map"]
        for law, row in compared["table"].items()
        if (row.get("screened") or row.get("settled")) and row.get("map")
    }
    compared["departures"] = _law_departures(
        common, runs, record, screened, model=model, discrepancy=discrepancy
    )
    unresolved = shape_unresolved(comparison, compared["departures"])
    if unresolved is not None:
        compared["shape_unresolved"] = unresolved
        _warn_unresolved(prepared.name, comparison.verdict, unresolved, averaged is not None)
    return dataclasses.replace(
        summarised, record=record.replace(law_comparison=plain_data(compared))
    )


def _check_halves(
    comparison: LawComparison,
    prepared: PreparedRun,
    rng: np.random.Generator,
    settings: SamplerSettings,
    model: str,
    discrepancy: bool,
    progress: Callable[[str], None] | None = None,
) -> LawComparison:
    """The verdict of an adequate comparison fitted to each half of the motion
    (:func:`bayestribo.inference.halves.law_halves`); when they disagree the comparison
    is no longer adequate, and a :class:`~bayestribo.errors.MisfitWarning` says so.
    ``progress`` is told when the halves are fitted."""
    if not comparison.adequate or get_law(comparison.verdict).name == get_law("free").name:
        return comparison
    if progress is not None:
        progress(f"fitting {comparison.verdict} to each half of the motion")
    halves = law_halves(
        prepared,
        comparison.verdict,
        seed=int(rng.integers(2**31)),
        settings=settings,
        model=model,
        discrepancy=discrepancy,
    )
    if halves.agree:
        return dataclasses.replace(comparison, halves=halves.to_dict())
    checked = dataclasses.replace(comparison, adequate=False, halves=halves.to_dict())
    warn(
        f"{prepared.name or 'the run'}: {checked.describe()}. {halves.describe()} "
        "(result.law_comparison['halves'])",
        MisfitWarning,
    )
    return checked


def shape_unresolved(
    comparison: LawComparison, departures: Mapping[str, Any]
) -> dict[str, Any] | None:
    """The laws as good as an adequate verdict whose ΔE(A) has another shape than the
    verdict's over the analysed swings, or None.

    Laws the comparison cannot tell apart (PSIS-LOO, :mod:`bayestribo.inference.choice`)
    are chosen between by simplicity, not by the record. Where they agree on ΔE(A) the
    choice does not matter; where their log-log slopes over the analysed swings differ
    by more than :data:`~bayestribo.inference.dissipation.SHAPE_SLOPE_TOLERANCE`
    (friction's A¹ against drag's A²: ``departures[law]["law_slope"]``,
    :func:`_law_departures`), the record does not say which law dissipates, and the
    verdict's parameters are a measurement only if its law is the one.

    Parameters
    ----------
    comparison : LawComparison
        The comparison, halves checked.
    departures : mapping
        Each compared law's :func:`~bayestribo.inference.dissipation.shape_agreement`.

    Returns
    -------
    dict or None
        ``slopes`` (law -> log-log slope of its ΔE(A), the verdict's first) and
        ``others`` (the laws as good whose slope differs from the verdict's by more than
        the tolerance); None when the verdict is not adequate (its answer is already
        the turning points'), its slope is unknown, or no such law is as good.
    """
    if not comparison.adequate:
        return None
    verdict = departures.get(comparison.verdict) or {}
    own = verdict.get("law_slope")
    if own is None or not np.isfinite(own):
        return None
    slopes = {comparison.verdict: float(own)}
    others = []
    for law in comparison.as_good:
        row = comparison.table.get(law, {})
        found = departures.get(law) or {}
        slope = found.get("law_slope")
        if law == comparison.verdict or not row.get("adequate") or slope is None:
            continue
        if np.isfinite(slope) and abs(slope - own) > SHAPE_SLOPE_TOLERANCE:
            slopes[law] = float(slope)
            others.append(law)
    return {"slopes": slopes, "others": others} if others else None


def _warn_unresolved(
    name: str | None, verdict: str, unresolved: Mapping[str, Any], averaged: bool
) -> None:
    """Say that laws of other shapes are as good as the verdict (:func:`shape_unresolved`)."""
    slopes = unresolved["slopes"]
    shapes = ", ".join(f"{law} (ΔE ∝ A^{slope:.2f})" for law, slope in slopes.items())
    answer = (
        "the ΔE(A) averaged over the laws as good (result.dissipation) holds whichever it is"
        if averaged
        else "the turning points' ΔE(A) (result.turning_point_dissipation) holds whichever it is"
    )
    warn(
        f"{name or 'the run'}: laws whose energy lost per cycle has another shape are as "
        f"good as {verdict}: {shapes}. The record does not tell which law dissipates "
        f"(its swings span too little, or its noise is too large), so {verdict}'s "
        f"parameters are a measurement only if {verdict} is the law; {answer} "
        "(result.law_comparison['shape_unresolved']). A record over a wider range of "
        "swings, or --law NAME where the physics says which, settles it",
        ShapeUnresolvedWarning,
    )


#: Draws of each compared law from which its ΔE(A) is set beside the turning points'.
_DEPARTURE_DRAWS = 200


def _law_departures(
    common: PreparedRun,
    runs: Mapping[str, Sampled],
    record: FitRecord,
    optima: Mapping[str, Mapping[str, float]] | None = None,
    *,
    model: str = "exact",
    discrepancy: bool = False,
) -> dict[str, Any]:
    """How close each compared law's ΔE(A) comes to the turning points' (the law-free
    answer), by law: :func:`~bayestribo.inference.dissipation.shape_agreement` of its
    posterior mean at the record's swings, from :data:`_DEPARTURE_DRAWS` draws of the
    comparison's fit on the common preparation; for a law screened out at its optimum
    (``optima``: its values there by name), of its ΔE(A) at that optimum. Empty
    without a turning-point answer."""
    measured = record.turning_point_dissipation
    band = record.dissipation
    if not measured or not band or not band.get("amplitude"):
        return {}
    sensor = record.sensor or {}
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
    runs: Mapping[str, Sampled],
    comparison: LawComparison,
    record: FitRecord,
    final: tuple[PreparedRun, Sampled],
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
    if not comparison.adequate:
        return None
    band = record.dissipation
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
    frequency_sd = float(record.frequency_nuisance_sd or 0.0)
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
