"""From a recording to what the likelihood observes: the signal-processing layer.

Modules
-------
peaks
    Turning points (peaks) of a recorded free decay.
motion
    :func:`~bayestribo.signal.motion.motion_span`: release and end of motion found as
    a coherent oscillation above the rest noise, whatever the length of the rest.
spectrum
    :func:`~bayestribo.signal.spectrum.noise_spectrum`: the noise at rest as a Welch
    spectrum (mains lines, colour, autocovariance); the zero-phase mains notch.
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
from bayestribo.signal.motion import MotionSpan, motion_span
from bayestribo.signal.noise import NoiseModel, noise_model
from bayestribo.signal.spectrum import NoiseSpectrum, RestNoise, noise_spectrum, notch_filter

__all__ = [
    "EnergyDecay",
    "MotionSpan",
    "NoiseModel",
    "NoiseSpectrum",
    "PiData",
    "RestNoise",
    "energy_decay",
    "motion_span",
    "noise_model",
    "noise_spectrum",
    "notch_filter",
    "pi_data",
]
