"""From a recording to what the likelihood observes: the signal-processing layer.

Modules
-------
period
    :func:`~bayestribo.signal.period.dominant_period`: the record's period, the one
    estimator of the package (readers' checks, derivatives, search windows).
frequency
    The damped frequency from zero crossings, and its trend with the amplitude.
channels
    Displacement against the integral of the velocity (gain, delay), and the checks
    of channels and units every file read gets.
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

from __future__ import annotations

from bayestribo._lazy import lazy_exports

# Re-exported lazily: the readers use the light modules (period, frequency, channels)
# without loading scipy.signal and the decay analysis.
_LAZY: dict[str, str] = {
    "EnergyDecay": "bayestribo.signal.decay",
    "energy_decay": "bayestribo.signal.decay",
    "PiData": "bayestribo.signal.increments",
    "pi_data": "bayestribo.signal.increments",
    "MotionSpan": "bayestribo.signal.motion",
    "motion_span": "bayestribo.signal.motion",
    "NoiseModel": "bayestribo.signal.noise",
    "noise_model": "bayestribo.signal.noise",
    "NoiseSpectrum": "bayestribo.signal.spectrum",
    "RestNoise": "bayestribo.signal.spectrum",
    "noise_spectrum": "bayestribo.signal.spectrum",
    "notch_filter": "bayestribo.signal.spectrum",
    "dominant_period": "bayestribo.signal.period",
}

__all__ = sorted(_LAZY, key=lambda name: (name[0].islower(), name))


__getattr__, __dir__ = lazy_exports(__name__, _LAZY)
