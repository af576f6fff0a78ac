"""Bayesian fit of one run: emcee on the retrograde energy integral Π(τ).

The main entry is :func:`fit`; the pieces (noise model, Π increments, priors,
likelihood, posterior, sampler, result) are small modules of their own, each usable
alone.
"""

from bayestribo.fit.core import fit, prior_sensitivity
from bayestribo.fit.data import PiData, pi_data
from bayestribo.fit.likelihood import PiLikelihood
from bayestribo.fit.noise import NoiseModel, noise_model
from bayestribo.fit.posterior import Posterior
from bayestribo.fit.priors import LogUniform, Normal, PriorSet, Uniform, default_priors
from bayestribo.fit.result import FitResult
from bayestribo.fit.sampling import SamplerSettings

__all__ = [
    "FitResult",
    "LogUniform",
    "NoiseModel",
    "Normal",
    "PiData",
    "PiLikelihood",
    "Posterior",
    "PriorSet",
    "SamplerSettings",
    "Uniform",
    "default_priors",
    "fit",
    "noise_model",
    "pi_data",
    "prior_sensitivity",
]
