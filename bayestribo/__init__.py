"""bayestribo: friction and viscous damping of an oscillating contact, with honest uncertainty.

The package identifies the equivalent viscous damping ζ and the velocity-independent
kinetic friction μ_k from the free decay of a single-degree-of-freedom oscillator
(Rigaud et al., *Tribology International* 43 (2010) 320-329).

The one call most users need is :func:`fit` (a run or a file in, a
:class:`FitResult` out); ``docs/architecture.md`` maps the sub-packages:

model
    Physics: exact piecewise response and averaged closed forms of E(τ) and Π(τ).
io
    Files in and out: :class:`Run`, :func:`read_run`, :func:`write_run`, :func:`as_run`.
signal
    A recording becomes an energy decay, a noise model and Π increments.
inference
    One run's posterior in four steps (prepare, build_posterior, sample, summarise).
estimators
    Classical baselines (peak decrements, Feeny-Liang, the paper's least squares).
adequacy, population, campaign
    Model checks, the hierarchical model of repeats, many runs at once.
synthetic, acquisition, reports, cli
    Simulated recordings, the hardware link, notebook reports, the command line.
"""

from __future__ import annotations

from bayestribo._lazy import lazy_exports

__version__ = "0.1.0"

#: Seed of every random step when none is given: the sampler of a fit, the law
#: comparison, the adequacy check, a campaign and a report. Results record the seed
#: they used, so a number can be reproduced from the result alone.
DEFAULT_SEED: int = 0

# Public names re-exported lazily: module imports stay cheap for the command line,
# and each capability keeps its own module.
_LAZY: dict[str, str] = {
    "fit": "bayestribo.inference.fitting",
    "FitResult": "bayestribo.inference.result",
    "ParameterSummary": "bayestribo.summary",
    "QuantitySummary": "bayestribo.inference.quantities",
    "as_run": "bayestribo.io",
    "estimate_signals": "bayestribo.estimators",
    "Rig": "bayestribo.model.scaling",
    "Scaling": "bayestribo.model.scaling",
    "energy_decay": "bayestribo.signal.decay",
    "EnergyDecay": "bayestribo.signal.decay",
    "estimate_all": "bayestribo.estimators",
    "Estimate": "bayestribo.estimators",
    "Run": "bayestribo.io.run",
    "read_run": "bayestribo.io",
    "ReadOptions": "bayestribo.io.options",
    "FileFormat": "bayestribo.io.registry",
    "register_format": "bayestribo.io.registry",
    "write_run": "bayestribo.io",
    "simulate": "bayestribo.synthetic.recording",
    "DissipationLaw": "bayestribo.synthetic.setup",
    "LawParameters": "bayestribo.synthetic.setup",
    "Release": "bayestribo.synthetic.setup",
    "Sensor": "bayestribo.synthetic.setup",
    "fit_many": "bayestribo.campaign.fitting",
    "compare_dissipation_laws": "bayestribo.inference.comparison",
    "acquire_run": "bayestribo.acquisition",
    "recover_run": "bayestribo.acquisition",
    "check_adequacy": "bayestribo.adequacy",
    "run_report": "bayestribo.reports.notebooks",
}

__all__ = ["DEFAULT_SEED", "__version__", *sorted(_LAZY)]


__getattr__, __dir__ = lazy_exports(__name__, _LAZY)
