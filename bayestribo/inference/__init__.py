"""Bayesian inference for one run: emcee on the retrograde energy integral Π(τ).

The main entry is :func:`fit`, which is the four public steps of
:mod:`bayestribo.inference.pipeline`: :func:`prepare` (Π increments from a run),
:func:`build_posterior` (priors × likelihood, optional fixed parameters),
:func:`sample` (MAP start and emcee to convergence) and :func:`summarise` (a
:class:`FitResult`). The pieces (priors, likelihood, posterior, sampler, result) are
small modules of their own, each usable alone.
"""

from bayestribo._lazy import lazy_exports

# Re-exported lazily: importing the package (for its light modules, such as the fit
# specification the command line builds its options from) imports no numpy.
_LAZY: dict[str, str] = {
    "FitResult": "bayestribo.inference.result",
    "FitSpec": "bayestribo.inference.spec",
    "LogUniform": "bayestribo.inference.priors",
    "Normal": "bayestribo.inference.priors",
    "ParameterSummary": "bayestribo.summary",
    "PiLikelihood": "bayestribo.inference.likelihood",
    "Posterior": "bayestribo.inference.posterior",
    "PreparedRun": "bayestribo.inference.pipeline",
    "PriorSet": "bayestribo.inference.priors",
    "Quantity": "bayestribo.inference.quantities",
    "QuantitySummary": "bayestribo.inference.quantities",
    "Sampled": "bayestribo.inference.pipeline",
    "SamplerRun": "bayestribo.inference.sampling",
    "SamplerSettings": "bayestribo.inference.sampling",
    "Uniform": "bayestribo.inference.priors",
    "build_posterior": "bayestribo.inference.pipeline",
    "default_priors": "bayestribo.inference.priors",
    "fit": "bayestribo.inference.fitting",
    "prepare": "bayestribo.inference.pipeline",
    "prior_sensitivity": "bayestribo.inference.sensitivity",
    "run_ensembles": "bayestribo.inference.sampling",
    "sample": "bayestribo.inference.pipeline",
    "summarise": "bayestribo.inference.pipeline",
}

__all__ = sorted(_LAZY)

__getattr__, __dir__ = lazy_exports(__name__, _LAZY)
