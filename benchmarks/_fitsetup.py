"""The likelihood of a run as :func:`bayestribo.inference.fit` builds it (for benchmarks).

:func:`bayestribo.inference.fit` does not return its internal objects; the benchmarks
that need the same likelihood (an ODE forward model in its place, the Fisher
information) rebuild it here with the fit's steps and defaults: energy decay with
one skipped oscillation, the recording's noise model, 64 Π increments, equilibrium
nuisance priors of 1 % of y0 (offset) and 1 % of y0 over the window (drift).
"""

from __future__ import annotations

from typing import Any

from bayestribo.inference.likelihood import PiLikelihood
from bayestribo.signal.decay import energy_decay
from bayestribo.signal.increments import pi_data
from bayestribo.signal.noise import noise_model

__all__ = ["likelihood_of"]


def likelihood_of(run: Any, cls: type = PiLikelihood, grid_points: int = 64) -> Any:
    """The fit's likelihood of ``run`` (a :class:`bayestribo.io.run.Run`), as ``cls``."""
    decay = energy_decay(
        run.time, run.displacement, run.velocity, rig=run.rig(), skip_oscillations=1
    )
    noise = noise_model(decay, dict(run.metadata))
    data = pi_data(decay, noise, grid_points=grid_points, seed=0)
    return cls(
        data,
        model="exact",
        offset_sd=max(1e-2 * abs(data.y0), 1e-12),
        drift_sd=max(1e-2 * abs(data.y0) / data.tau_end, 1e-15),
    )
