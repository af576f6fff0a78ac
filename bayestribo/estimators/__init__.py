"""Classical estimators of ζ and μ_k: peak decrements and the paper's least squares.

These are the methods a tribologist would use instead of the Bayesian fit: baselines
to compare against, starting points for the sampler, and quick point estimates.

Modules
-------
result
    :class:`Estimate` (one result type) and :class:`EstimateTable`.
decrement
    Viscous-only logarithmic decrement and exponential envelope (ζ₀).
feeny_liang
    Successive-peak decrement (Eq. 20-21).
nonsuccessive
    Non-successive peaks (Eq. 22-25).
energy_ls
    Least squares on Π(τ) with the averaged or the exact model (Eq. 40-42).
all
    :func:`estimate_all`: every applicable method on one run;
    :func:`estimate_signals`: the same on bare arrays t, x, v.
"""

from __future__ import annotations

from bayestribo._lazy import lazy_exports

# The successive-peak estimate (the fit's starting point) is imported at once: its
# function has its module's name, which the import of that module would otherwise
# leave bound here. The other methods, and their SciPy modules, are re-exported lazily.
from bayestribo.estimators.feeny_liang import feeny_liang as feeny_liang

_LAZY: dict[str, str] = {
    "estimate_all": "bayestribo.estimators.all",
    "estimate_signals": "bayestribo.estimators.all",
    "exponential_envelope": "bayestribo.estimators.decrement",
    "log_decrement": "bayestribo.estimators.decrement",
    "energy_data": "bayestribo.estimators.energy_ls",
    "energy_least_squares": "bayestribo.estimators.energy_ls",
    "nonsuccessive_peaks": "bayestribo.estimators.nonsuccessive",
    "Estimate": "bayestribo.estimators.result",
    "EstimateTable": "bayestribo.estimators.result",
    "friction_fraction": "bayestribo.estimators.result",
}

__all__ = sorted([*_LAZY, "feeny_liang"], key=lambda name: (name[0].islower(), name))


__getattr__, __dir__ = lazy_exports(__name__, _LAZY)
