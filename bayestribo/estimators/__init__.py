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

import importlib
from typing import Any

# Loaded on first use (PEP 562): the command line lists the methods
# (bayestribo.estimators.methods) without importing SciPy's optimisers and statistics.
_WHERE = {
    "estimate_all": "all",
    "estimate_signals": "all",
    "exponential_envelope": "decrement",
    "log_decrement": "decrement",
    "energy_data": "energy_ls",
    "energy_least_squares": "energy_ls",
    "feeny_liang": "feeny_liang",
    "nonsuccessive_peaks": "nonsuccessive",
    "Estimate": "result",
    "EstimateTable": "result",
    "friction_fraction": "result",
}


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        module = importlib.import_module(f"bayestribo.estimators.{_WHERE[name]}")
        return getattr(module, name)
    raise AttributeError(f"module 'bayestribo.estimators' has no attribute {name!r}")


__all__ = [
    "Estimate",
    "EstimateTable",
    "energy_data",
    "energy_least_squares",
    "estimate_all",
    "estimate_signals",
    "exponential_envelope",
    "feeny_liang",
    "friction_fraction",
    "log_decrement",
    "nonsuccessive_peaks",
]
