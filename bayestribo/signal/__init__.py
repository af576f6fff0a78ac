"""From a recording to what the likelihood observes: the signal-processing layer.

Modules
-------
peaks
    Turning points (peaks) of a recorded free decay.
decay
    :func:`energy_decay`: the one place a recording becomes an energy decay E(τ):
    release, skipped oscillations, equilibrium, end of motion, noise at rest.
noise
    :func:`noise_model`: nominal instrument resolution against the noise measured at
    rest; the one used downstream.
increments
    :func:`pi_data`: Π(τ) on a grid as independent increments, their quadrature
    weights, the noise bias of E and the increment variances.
"""

from bayestribo.signal.decay import EnergyDecay, energy_decay
from bayestribo.signal.increments import PiData, pi_data
from bayestribo.signal.noise import NoiseModel, noise_model

__all__ = ["EnergyDecay", "NoiseModel", "PiData", "energy_decay", "noise_model", "pi_data"]
