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

from bayestribo.estimators.all import estimate_all, estimate_signals
from bayestribo.estimators.decrement import exponential_envelope, log_decrement
from bayestribo.estimators.energy_ls import energy_data, energy_least_squares
from bayestribo.estimators.feeny_liang import feeny_liang
from bayestribo.estimators.nonsuccessive import nonsuccessive_peaks
from bayestribo.estimators.result import Estimate, EstimateTable, friction_fraction

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
