"""Bayesian inference for one run: emcee on the retrograde energy integral Π(τ).

The main entry is :func:`fit`, which is the stages of :mod:`bayestribo.inference.
pipeline` in a row, each a module of its own: :func:`prepare` (Π increments from a
run, :mod:`~bayestribo.inference.preparation`), :func:`build_posterior` (priors ×
likelihood, optional fixed parameters, :mod:`~bayestribo.inference.build`), the start
(:mod:`~bayestribo.inference.start`), :func:`sample` (emcee to convergence,
:mod:`~bayestribo.inference.chains`), :func:`check` (:mod:`~bayestribo.inference.checks`)
and :func:`summarise` (a :class:`FitResult`, :mod:`~bayestribo.inference.summarising`);
``law="auto"`` compares, chooses and refits on top of them
(:mod:`~bayestribo.inference.auto`). The pieces (priors, likelihood, posterior,
sampler, result) are small modules of their own, each usable alone.
"""

from bayestribo._lazy import lazy_exports

# Re-exported lazily: importing the package (for its light modules, such as the fit
# specification the command line builds its options from) imports no numpy.
_LAZY: dict[str, str] = {
    "FitRecord": "bayestribo.inference.fit_record",
    "FitResult": "bayestribo.inference.result",
    "FitSpec": "bayestribo.inference.spec",
    "LogUniform": "bayestribo.inference.priors",
    "Normal": "bayestribo.inference.priors",
    "ParameterSummary": "bayestribo.summary",
    "PiLikelihood": "bayestribo.inference.likelihood",
    "Posterior": "bayestribo.inference.posterior",
    "PreparedRun": "bayestribo.inference.types",
    "PriorSet": "bayestribo.inference.priors",
    "Quantity": "bayestribo.inference.quantities",
    "QuantitySummary": "bayestribo.inference.quantities",
    "Sampled": "bayestribo.inference.types",
    "SamplerRun": "bayestribo.inference.sampling",
    "SamplerSettings": "bayestribo.inference.sampling",
    "Uniform": "bayestribo.inference.priors",
    "build_posterior": "bayestribo.inference.build",
    "check": "bayestribo.inference.checks",
    "default_priors": "bayestribo.inference.priors",
    "fit": "bayestribo.inference.fitting",
    "prepare": "bayestribo.inference.preparation",
    "prior_sensitivity": "bayestribo.inference.sensitivity",
    "run_ensembles": "bayestribo.inference.sampling",
    "sample": "bayestribo.inference.chains",
    "summarise": "bayestribo.inference.summarising",
}

__all__ = sorted(_LAZY)

__getattr__, __dir__ = lazy_exports(__name__, _LAZY)
