"""The population of repeats: across-run statements from per-run posteriors.

Each run is fitted alone; the population treats the runs' ζ and μ_k as draws from a
normal population per group (any metadata key) with a mean and a between-run standard
deviation σ, and infers those hyperparameters by reusing each run's posterior samples
with its prior divided out (importance-weighted per-run marginal likelihood,
:mod:`~bayestribo.population.likelihood`).

Modules
-------
samples
    :class:`RunSamples`: per-run samples with their prior densities.
hyperpriors
    Scale-free (default), half-Cauchy and half-normal priors on σ.
likelihood
    The population likelihood from per-run samples.
sampler
    emcee sampling of the hyperparameters, seeded, with diagnostics.
groups
    :func:`population`: per-group and pooled means and σ, group differences.
trend
    :func:`trend`: slope of the population mean against a covariate (load).
"""

from __future__ import annotations

from bayestribo.population.groups import POOLED, GroupPosterior, Population, difference, population
from bayestribo.population.hyperpriors import (
    DEFAULT_SIGMA_SCALES,
    HalfCauchy,
    HalfNormal,
    LogUniform,
    ScaleFree,
    sigma_priors,
)
from bayestribo.population.likelihood import MarginalLikelihood
from bayestribo.population.samples import RunSamples, as_run_samples, run_samples
from bayestribo.population.trend import Trend, slope_probabilities, trend
from bayestribo.summary import summarize

__all__ = [
    "DEFAULT_SIGMA_SCALES",
    "POOLED",
    "GroupPosterior",
    "HalfCauchy",
    "HalfNormal",
    "LogUniform",
    "MarginalLikelihood",
    "Population",
    "RunSamples",
    "ScaleFree",
    "Trend",
    "as_run_samples",
    "difference",
    "population",
    "run_samples",
    "sigma_priors",
    "slope_probabilities",
    "summarize",
    "trend",
]
