"""What a campaign keeps of a fit: a digest, so that memory does not grow with the runs.

A campaign's analysis needs of each fit its law, metadata, convergence, the parameters
at a prior bound, the posterior summaries of the quantities it compares across runs
(:mod:`bayestribo.campaign.quantities`: ζ and μ_k in the paper's law, each law's own
otherwise), and a seeded subset of their draws with the log prior density there (the
population likelihood uses at most a few hundred draws per run). :func:`digest_fit`
takes exactly that from a fit result; the campaign keeps the digest and lets the fit
go (it is on disk, in the catalog). The digest gives the same analysis as the fit: its
subset is the one :func:`~bayestribo.population.samples.run_samples` draws from the
fit with the same seed and run name, and its summaries are those of all the draws.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.campaign.laws import comparison_digest
from bayestribo.campaign.quantities import campaign_quantities, quantity_draws
from bayestribo.errors import BayestriboError
from bayestribo.population.samples import RunSamples, run_samples
from bayestribo.summary import summarize

__all__ = ["FitDigest", "digest_fit"]

#: The parameters of the paper's campaign (Rigaud et al. 2010, section 2.5).
PARAMETERS: tuple[str, ...] = ("zeta", "mu_k")


@dataclass(frozen=True)
class FitDigest:
    """What a campaign's analysis uses of one fit (a fit-like object, far smaller).

    Attributes
    ----------
    run_name : str
        The run's identity.
    metadata : dict
        The run's metadata.
    parameter_names : tuple of str
        The fit's sampled parameters.
    converged : bool
        Whether the fit's sampler converged.
    at_prior_bound : list
        The fit's posteriors piled on a prior bound.
    prob : float
        Probability of the summaries' intervals.
    summaries : dict of str to dict
        Summaries of the kept quantities over all the fit's draws
        (:func:`bayestribo.summary.summarize`; ``kind`` ``"bound"`` with the interval
        from the prior's lower end to the bound where the data do not constrain one, as
        the fit's own summary).
    draws : dict of str to ndarray
        The seeded subset of draws of each kept quantity.
    log_prior : dict of str to ndarray
        Each quantity's log prior density at its subset of draws.
    law : str or None
        The fit's dissipation law.
    quantities : dict of str to dict
        Each kept quantity's symbol, unit, label, term and sign
        (:meth:`bayestribo.campaign.quantities.CampaignQuantity.describe`).
    left_out : dict of str to str
        Sampled parameters not compared across runs, with why.
    comparison : dict or None
        What the choice of a group's law needs of the fit's law comparison (a fit with
        ``law="auto"``; :func:`bayestribo.campaign.laws.comparison_digest`).
    turning_points : dict or None
        The law-free ΔE(A) from the run's turning points (``amplitude``, ``mean``,
        ``sd``, ``unit``, ``amplitude_unit``), for :mod:`bayestribo.campaign.dissipation`.
    dissipation : dict or None
        The law's ΔE(A) band (``law``, ``amplitude``, ``mean``, ``interval``, ``unit``,
        ``amplitude_unit``, ``prob``), read at a swing its group shares
        (:mod:`bayestribo.campaign.bands`).
    """

    run_name: str
    metadata: dict[str, Any]
    parameter_names: tuple[str, ...]
    converged: bool
    at_prior_bound: list[Any]
    prob: float
    summaries: dict[str, dict[str, Any]]
    draws: dict[str, NDArray[np.float64]] = field(repr=False)
    log_prior: dict[str, NDArray[np.float64]] = field(repr=False)
    law: str | None = None
    quantities: dict[str, dict[str, Any]] = field(default_factory=dict)
    left_out: dict[str, str] = field(default_factory=dict)
    comparison: dict[str, Any] | None = None
    turning_points: dict[str, Any] | None = None
    dissipation: dict[str, Any] | None = None

    def samples(self, name: str) -> NDArray[np.float64]:
        """The subset of draws of ``name``."""
        if name not in self.draws:
            raise KeyError(f"{name!r} is not kept in this digest; it has {sorted(self.draws)}")
        return self.draws[name]

    def prior_logpdf(self, name: str, values: ArrayLike) -> NDArray[np.float64]:
        """The log prior density of ``name`` at its own draws (the only values kept).

        Raises
        ------
        ValueError
            For other values: the digest does not keep the prior itself.
        """
        if name not in self.draws:
            raise KeyError(f"{name!r} is not kept in this digest; it has {sorted(self.draws)}")
        if not np.array_equal(np.asarray(values, dtype=float), self.draws[name]):
            raise ValueError(f"a fit digest gives the log prior of {name!r} at its own draws only")
        return self.log_prior[name]

    def summary_at(self, prob: float) -> dict[str, dict[str, Any]]:
        """The summaries, which hold for :attr:`prob` only.

        Raises
        ------
        BayestriboError
            For another probability.
        """
        if prob != self.prob:
            raise BayestriboError(
                f"prob: this digest summarises at {self.prob}, not at {prob}; digest the "
                "fits with the analysis' probability"
            )
        return self.summaries


def digest_fit(
    result: Any,
    *,
    prob: float = 0.95,
    max_samples: int | None = 300,
    seed: int = 0,
    name: str | None = None,
    parameters: Sequence[str] | None = None,
) -> FitDigest:
    """The digest of a fit result that a campaign analysis needs.

    Parameters
    ----------
    result : fit result
        With ``samples``, ``prior_logpdf``, ``metadata`` (as
        :class:`bayestribo.inference.FitResult`); a :class:`FitDigest` is returned as it
        is.
    prob : float
        Probability of the summaries' intervals (the analysis' ``prob``).
    max_samples, seed
        The subset of draws kept, as the analysis draws it
        (:func:`bayestribo.campaign.analysis.analyse_campaign`).
    name : str, optional
        The run's identity; default its metadata ``run_id``.
    parameters : sequence of str, optional
        Parameters kept as sampled, those of them the fit has; default the
        quantities of the fit's law that a campaign compares
        (:func:`bayestribo.campaign.quantities.campaign_quantities`).
    """
    if isinstance(result, FitDigest):
        return result
    metadata = dict(getattr(result, "metadata", {}) or {})
    name = name or str(metadata.get("run_id") or getattr(result, "run_name", None) or "run")
    names = tuple(getattr(result, "parameter_names", ()) or ())
    draws: dict[str, NDArray[np.float64]] = {}
    log_prior: dict[str, NDArray[np.float64]] = {}
    summaries: dict[str, dict[str, Any]] = {}
    described: dict[str, dict[str, Any]] = {}
    left_out: dict[str, str] = {}
    if parameters is None:
        quantities, left_out = campaign_quantities(result)
        for q in quantities:
            try:
                values, density = quantity_draws(result, q)
            except (KeyError, ValueError):
                continue  # no prior of its own: not kept for a population
            summaries[q.name] = _summary(result, q.parameter, values, q.factor, prob)
            kept = _subset(name, q.name, values, density, metadata, max_samples, seed)
            draws[q.name] = kept.values[q.name]
            log_prior[q.name] = kept.log_prior
            described[q.name] = q.describe()
    else:
        for key in parameters:
            try:
                everything = result.samples(key)
            except (KeyError, ValueError):
                continue
            summaries[key] = _summary(result, key, everything, 1.0, prob)
            try:
                kept = run_samples(result, (key,), max_samples=max_samples, seed=seed, name=name)
            except BayestriboError:
                continue  # no prior of its own: summarised, not kept for a population
            draws[key] = kept.values[key]
            log_prior[key] = kept.log_prior
    return FitDigest(
        run_name=name,
        metadata=metadata,
        parameter_names=names,
        converged=bool(getattr(result, "converged", True)),
        at_prior_bound=list(getattr(result, "at_prior_bound", []) or []),
        prob=prob,
        summaries=summaries,
        draws=draws,
        log_prior=log_prior,
        law=str(getattr(result, "law", None) or "") or None,
        quantities=described,
        left_out=left_out,
        comparison=comparison_digest(getattr(result, "law_comparison", None)),
        turning_points=_turning_points(result),
        dissipation=_law_band(result),
    )


def _summary(
    result: Any, parameter: str, values: NDArray[np.float64], factor: float, prob: float
) -> dict[str, Any]:
    """The summary of ``values`` = ``factor`` × the draws of ``parameter``, as the fit's
    own (:meth:`bayestribo.inference.FitResult.summary`): where the data do not constrain
    it, ``kind`` ``"bound"`` and the interval from the prior's lower end to the bound
    (:func:`~bayestribo.inference.flatness.bound_interval`), never a central interval
    of a prior; a static friction whose lowest step starts at its prior's end, its
    interval from there (:func:`~bayestribo.inference.flatness.prior_end_interval`)."""
    from bayestribo.inference.flatness import prior_end_interval

    out = summarize(values, prob)
    if not (np.isfinite(factor) and factor > 0):
        return out
    try:
        from_end = prior_end_interval(result, parameter, np.asarray(values) / factor, prob)
    except (KeyError, ValueError, AttributeError):
        return out
    if from_end is not None:
        (low, high), kind = from_end
        out["interval"] = [float(factor * low), float(factor * high)]
        out["kind"] = kind
    return out


def _turning_points(result: Any) -> dict[str, Any] | None:
    """The law-free ΔE(A) band a digest keeps (its mean and sd at each swing)."""
    band = getattr(result, "turning_point_dissipation", None)
    if not isinstance(band, dict) or not band.get("amplitude"):
        return None
    keys = ("amplitude", "mean", "sd", "unit", "amplitude_unit")
    return {k: band.get(k) for k in keys}


def _law_band(result: Any) -> dict[str, Any] | None:
    """The law's ΔE(A) band a digest keeps (its mean and interval at each swing)."""
    band = getattr(result, "dissipation", None)
    if not isinstance(band, dict) or not band.get("amplitude") or "interval" not in band:
        return None
    keys = ("law", "amplitude", "mean", "interval", "unit", "amplitude_unit", "prob")
    return {k: band.get(k) for k in keys}


class _Drawn:
    """A fit-like view of one quantity's draws, for :func:`run_samples`' seeded subset."""

    def __init__(self, key: str, values: NDArray, density: NDArray, metadata: dict) -> None:
        self._key, self._values, self._density = key, values, density
        self.metadata = metadata

    def samples(self, name: str) -> NDArray[np.float64]:
        return self._values

    def prior_logpdf(self, name: str, values: ArrayLike) -> NDArray[np.float64]:
        return self._density


def _subset(
    name: str,
    key: str,
    values: NDArray,
    density: NDArray,
    metadata: dict[str, Any],
    max_samples: int | None,
    seed: int,
) -> RunSamples:
    """The seeded subset :func:`run_samples` draws, of one quantity's draws."""
    return run_samples(
        _Drawn(key, values, density, metadata),
        (key,),
        max_samples=max_samples,
        seed=seed,
        name=name,
    )
