"""Bayesian inference for one run: emcee on the retrograde energy integral Π(τ).

The main entry is :func:`fit`, which is the four public steps of
:mod:`bayestribo.inference.pipeline`: :func:`prepare` (Π increments from a run),
:func:`build_posterior` (priors × likelihood, optional fixed parameters),
:func:`sample` (MAP start and emcee to convergence) and :func:`summarise` (a
:class:`FitResult`). The pieces (priors, likelihood, posterior, sampler, result) are
small modules of their own, each usable alone.
"""

from bayestribo.inference.fitting import fit
from bayestribo.inference.likelihood import PiLikelihood
from bayestribo.inference.pipeline import (
    PreparedRun,
    Sampled,
    build_posterior,
    prepare,
    sample,
    summarise,
)
from bayestribo.inference.posterior import Posterior
from bayestribo.inference.priors import LogUniform, Normal, PriorSet, Uniform, default_priors
from bayestribo.inference.result import FitResult
from bayestribo.inference.sampling import SamplerRun, SamplerSettings, run_ensembles
from bayestribo.inference.sensitivity import prior_sensitivity
from bayestribo.summary import ParameterSummary

__all__ = [
    "FitResult",
    "LogUniform",
    "Normal",
    "ParameterSummary",
    "PiLikelihood",
    "Posterior",
    "PreparedRun",
    "PriorSet",
    "Sampled",
    "SamplerRun",
    "SamplerSettings",
    "Uniform",
    "build_posterior",
    "default_priors",
    "fit",
    "prepare",
    "prior_sensitivity",
    "run_ensembles",
    "sample",
    "summarise",
]
