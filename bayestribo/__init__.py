"""bayestribo: friction and viscous damping of an oscillating contact, with honest uncertainty.

The package identifies the equivalent viscous damping ζ and the velocity-independent
kinetic friction μ_k from the free decay of a single-degree-of-freedom oscillator
(Rigaud et al., *Tribology International* 43 (2010) 320-329).

Sub-modules
-----------
scaling
    Rig parameters and the dimensionless scaling (Eq. 6, 9-11).
model
    Exact piecewise response and averaged closed forms of E(τ) and Π(τ).
decay
    Energy decay curve of a recording.
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

# Public names re-exported lazily: module imports stay cheap for the command line,
# and each capability keeps its own module.
_LAZY: dict[str, str] = {
    "Rig": "bayestribo.model.scaling",
    "Scaling": "bayestribo.model.scaling",
    "energy_decay": "bayestribo.signal.decay",
    "EnergyDecay": "bayestribo.signal.decay",
    "estimate_all": "bayestribo.estimators",
    "Estimate": "bayestribo.estimators",
    "Run": "bayestribo.io.run",
    "read_run": "bayestribo.io",
    "write_run": "bayestribo.io",
    "simulate": "bayestribo.synthetic.recording",
    "fit_many": "bayestribo.campaign.fitting",
    "compare_dissipation_laws": "bayestribo.inference.comparison",
    "acquire_run": "bayestribo.acquisition",
    "recover_run": "bayestribo.acquisition",
    "check_adequacy": "bayestribo.adequacy",
    "run_report": "bayestribo.reports.notebooks",
}

__all__ = ["__version__", *sorted(_LAZY)]


def __getattr__(name: str) -> Any:
    try:
        module = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'bayestribo' has no attribute {name!r}") from None
    return getattr(importlib.import_module(module), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
