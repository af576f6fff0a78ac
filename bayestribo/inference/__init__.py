"""Bayesian fit of one run: emcee on the retrograde energy integral Π(τ).

The main entry is :func:`fit`; the pieces (noise model, Π increments, priors,
likelihood, posterior, sampler, result) are small modules of their own, each usable
alone.
"""

from bayestribo.inference.fitting import fit, prior_sensitivity
from bayestribo.inference.likelihood import PiLikelihood
from bayestribo.inference.posterior import Posterior
from bayestribo.inference.priors import LogUniform, Normal, PriorSet, Uniform, default_priors
from bayestribo.inference.result import FitResult
from bayestribo.inference.sampling import SamplerSettings
from bayestribo.signal.increments import PiData, pi_data
from bayestribo.signal.noise import NoiseModel, noise_model

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
