"""Trend of the population against a covariate (e.g. load): slope with its probability.

Model: θ_ik ~ Normal(a_k + b_k (x_i − x̄), σ_k²) over all the runs given, with x_i a
numeric metadata value (default ``load_N``), flat priors on a_k and b_k and the σ prior
of :mod:`bayestribo.population.hyperpriors`. The covariate is centred at the mean x̄
of the runs for sampling; the reported intercept is at x = 0.

"Is the slope non-zero?" is answered with posterior probabilities:

* ``prob_positive`` = P(b > 0 | data), ``prob_negative`` = P(b < 0 | data);
* ``prob_sign`` = max of the two: the posterior probability of the more probable sign.
  With flat priors it is one minus the one-sided tail area, so under no trend it is
  uniform on [0.5, 1] and ``prob_sign > 0.975`` happens in about 5 % of campaigns
  (a two-sided 5 % test);
* with a region of practical equivalence ``rope`` (|b| <= rope counts as "no trend"),
  ``prob_outside_rope`` = P(|b| > rope | data) and ``prob_inside_rope``.
"""

from __future__ import annotations

import zlib
from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import BayestriboError
from bayestribo.population.hyperpriors import SigmaPriorSpec, resolve, sigma_priors
from bayestribo.population.likelihood import MarginalLikelihood
from bayestribo.population.sampler import sample_hyperparameters
from bayestribo.population.samples import FitLike, RunSamples, as_run_samples
from bayestribo.summary import ParameterSummary, summarize

__all__ = ["Trend", "slope_probabilities", "trend"]


def slope_probabilities(slope: NDArray[np.float64], rope: float | None = None) -> dict[str, Any]:
    """Posterior probabilities of the sign of a slope, and of leaving a ROPE.

    Parameters
    ----------
    slope : array
        Posterior samples of the slope.
    rope : float, optional
        Half-width of the region of practical equivalence [parameter units per
        covariate unit].
    """
    s = np.asarray(slope, dtype=float)
    pos, neg = float(np.mean(s > 0)), float(np.mean(s < 0))
    out: dict[str, Any] = {"prob_positive": pos, "prob_negative": neg, "prob_sign": max(pos, neg)}
    if rope is not None:
        if not (np.isfinite(rope) and rope >= 0):
            raise BayestriboError(f"rope: expected a finite number >= 0, got {rope!r}")
        outside = float(np.mean(np.abs(s) > rope))
        out.update(
            {"rope": float(rope), "prob_outside_rope": outside, "prob_inside_rope": 1.0 - outside}
        )
    return out


@dataclass(frozen=True)
class Trend:
    """Posterior of a linear trend of the population against a covariate.

    Attributes
    ----------
    covariate : str
        Metadata key of the covariate.
    center : float
        x̄, the mean covariate of the runs.
    runs : tuple of str
        The runs' names.
    parameters : tuple of str
        Parameter names.
    intercept, slope, sigma : dict of str to ndarray
        Posterior samples of a_k − b_k x̄ (the mean at x = 0), b_k, σ_k.
    rope : dict of str to float
        ROPE half-width per parameter (absent: none).
    diagnostics : dict
        Sampler diagnostics.
    span : tuple of float or None
        The smallest and largest covariate of the runs [the covariate's unit]: the
        population mean is summarised at both (:meth:`ends`).
    """

    covariate: str
    center: float
    runs: tuple[str, ...]
    parameters: tuple[str, ...]
    intercept: dict[str, NDArray[np.float64]]
    slope: dict[str, NDArray[np.float64]]
    sigma: dict[str, NDArray[np.float64]]
    rope: dict[str, float] = field(default_factory=dict)
    diagnostics: dict[str, Any] = field(default_factory=dict)
    span: tuple[float, float] | None = None

    def mean_at(self, parameter: str, x: float) -> NDArray[np.float64]:
        """Posterior samples of the population mean of ``parameter`` at covariate ``x``."""
        return self.intercept[parameter] + self.slope[parameter] * x

    def slope_summary(self, parameter: str, prob: float = 0.95) -> dict[str, Any]:
        """Summary of the slope with the sign and ROPE probabilities."""
        if parameter not in self.slope:
            raise BayestriboError(f"parameter: {parameter!r} is not among {list(self.parameters)}")
        out = summarize(self.slope[parameter], prob)
        out.update(slope_probabilities(self.slope[parameter], self.rope.get(parameter)))
        return out

    def ends(self, prob: float = 0.95) -> dict[str, list[dict[str, Any]]]:
        """Per parameter, the population mean at the smallest and the largest covariate
        of the runs (:attr:`span`): each :func:`~bayestribo.summary.summarize` of its
        draws with ``at``, the covariate there; empty without a span."""
        if self.span is None:
            return {}
        return {
            p: [{"at": float(x), **summarize(self.mean_at(p, float(x)), prob)} for x in self.span]
            for p in self.parameters
        }

    def summary(self, prob: float = 0.95) -> dict[str, dict[str, ParameterSummary]]:
        """Per parameter, posterior summaries of the slope, the intercept and σ."""
        return {
            p: {
                "slope": ParameterSummary.from_samples(self.slope[p], prob),
                "intercept": ParameterSummary.from_samples(self.intercept[p], prob),
                "sigma": ParameterSummary.from_samples(self.sigma[p], prob),
            }
            for p in self.parameters
        }

    def to_dict(self, prob: float = 0.95) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "covariate": self.covariate,
            "center": self.center,
            "runs": list(self.runs),
            "parameters": {
                p: {
                    "slope": self.slope_summary(p, prob),
                    "intercept": summarize(self.intercept[p], prob),
                    "sigma": summarize(self.sigma[p], prob),
                }
                for p in self.parameters
            },
            "diagnostics": dict(self.diagnostics),
            "span": None if self.span is None else [float(x) for x in self.span],
            "mean_at_ends": self.ends(prob),
        }


def trend(
    runs: Iterable[RunSamples | FitLike],
    covariate: str = "load_N",
    parameters: Sequence[str] = ("zeta", "mu_k"),
    *,
    rope: Mapping[str, float] | None = None,
    sigma_prior: Mapping[str, SigmaPriorSpec | float] | None = None,
    seed: int = 0,
    max_samples: int | None = 1000,
    n_walkers: int | None = None,
    max_steps: int = 10_000,
    progress: bool = False,
    non_negative: Collection[str] | None = None,
) -> Trend:
    """Infer the linear trend of the population of runs against a numeric covariate.

    Parameters
    ----------
    runs : iterable of RunSamples or fit results
        Per-run posteriors; each run's metadata must hold a number under ``covariate``.
    covariate : str
        Metadata key, default ``"load_N"`` [N].
    parameters : sequence of str
        Parameters modelled jointly.
    rope : mapping, optional
        Per parameter, the half-width of a region of practical equivalence of the slope.
    sigma_prior, seed, max_samples, n_walkers, max_steps, progress, non_negative
        As in :func:`bayestribo.population.population`.

    Raises
    ------
    BayestriboError
        If a run has no numeric covariate, or fewer than two distinct values are given.
    """
    parameters = tuple(parameters)
    samples = as_run_samples(runs, parameters, max_samples=max_samples, seed=seed)
    samples.sort(key=lambda r: r.name)  # results independent of the runs' order
    x = []
    for run in samples:
        value = run.metadata.get(covariate)
        if not isinstance(value, int | float) or isinstance(value, bool) or not np.isfinite(value):
            raise BayestriboError(
                f"run {run.name!r}: metadata {covariate!r} should be a finite number, got {value!r}"
            )
        x.append(float(value))
    xs = np.array(x)
    if len(np.unique(xs)) < 2:
        raise BayestriboError(
            f"{covariate}: a trend needs runs at two or more distinct values, got {sorted(set(x))}"
        )
    rope = dict(rope or {})
    unknown = sorted(set(rope) - set(parameters))
    if unknown:
        raise BayestriboError(f"rope: {unknown} not among the parameters {list(parameters)}")
    priors = {
        p: resolve(prior, [np.std(r.values[p]) for r in samples])
        for p, prior in sigma_priors(parameters, sigma_prior).items()
    }
    center = float(xs.mean())
    design = np.column_stack([np.ones_like(xs), xs - center])
    like = MarginalLikelihood(samples, parameters, design)
    group_seed = int(
        np.random.SeedSequence([seed, zlib.crc32(f"trend:{covariate}".encode())]).generate_state(1)[
            0
        ]
    )
    hyper = sample_hyperparameters(
        like,
        [priors[p] for p in parameters],
        seed=group_seed,
        n_walkers=n_walkers,
        max_steps=max_steps,
        progress=progress,
        non_negative=non_negative,
    )
    slope = {p: hyper.beta[:, 1, j] for j, p in enumerate(parameters)}
    intercept = {p: hyper.beta[:, 0, j] - slope[p] * center for j, p in enumerate(parameters)}
    return Trend(
        covariate=covariate,
        center=center,
        runs=tuple(r.name for r in samples),
        parameters=parameters,
        intercept=intercept,
        slope=slope,
        sigma={p: hyper.sigma[:, j] for j, p in enumerate(parameters)},
        rope={k: float(v) for k, v in rope.items()},
        diagnostics=hyper.diagnostics
        | {"sigma_prior": {p: priors[p].describe() for p in parameters}},
        span=(float(xs.min()), float(xs.max())),
    )
