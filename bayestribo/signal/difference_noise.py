"""A channel's white noise from its second differences, where no stretch of rest is long.

The noise of a record is measured at rest (:func:`bayestribo.signal.motion.block_noise`:
blocks of two periods about their line). A slow rig's record may hold no such block: a
rest of a second before the release and after the stop of a 1 Hz oscillator, say. Its
noise can still be read off the motion itself where the record holds many samples a
period: the second difference of a sinusoid of amplitude A sampled N times a period is
at most (2π/N)² A, while white noise's is √6 σ, so over a record of hundreds of samples a
period the second differences are the noise's. A kink of the signal (the friction's
reversal at a turning point, the stop) moves a few of them, and their median absolute
deviation does not see those.

The estimate holds for white noise only. Noise coloured at the sample's scale (an
anti-alias filter, a digital low-pass) has second differences smaller than its σ: the
lag-one correlation of white noise's second differences is −2/3 (the weights 1, −2, 1),
and the estimate is returned only where the record's is within
:data:`WHITENESS_TOLERANCE` (or 4 of its standard errors) of that. The test is weak for
a filter that keeps a floor at high frequencies (an RC's): one at a quarter of the
sample rate passes it, and the σ read is then 0.87 of the noise's. Where the signal's
own second differences reach :data:`SIGNAL_SHARE` of the noise's, or the channel is
flat (a coarse digitiser's steps wider than its noise), there is none either.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "MIN_SAMPLES",
    "SIGNAL_SHARE",
    "WHITENESS_ERRORS",
    "WHITENESS_TOLERANCE",
    "difference_noise",
]

#: Fewest samples for the estimate (its median absolute deviation's relative standard
#: error is about 1.2/√n: 5 % at 500).
MIN_SAMPLES = 500
#: Largest ratio of the signal's second differences, (2π/N)² times the record's largest
#: excursion from its median for N samples a period, to the noise's (√6 σ).
SIGNAL_SHARE = 0.1
#: Largest departure of the second differences' lag-one correlation from white noise's
#: −2/3, and that in its standard errors at n samples (about 0.9/√n): a one-pole
#: low-pass at a quarter of the sample rate (−0.61) is then told from white noise on
#: records of a few thousand samples, and the σ it gives is at least 0.87 of the noise's
#: (0.6 at a tenth of the sample rate, whose −0.55 is refused).
WHITENESS_TOLERANCE = 0.05
WHITENESS_ERRORS = 4.0
#: Lag-one correlation of the second differences of white noise.
WHITE_LAG_ONE = -2.0 / 3.0
#: Standard deviation of a normal variable over its median absolute deviation.
_MAD_SD = 1.482602218505602


def _mad(values: np.ndarray) -> float:
    """Median absolute deviation of ``values`` from their median."""
    return float(np.median(np.abs(values - np.median(values))))


def difference_noise(signal: ArrayLike, samples_per_period: float) -> float | None:
    """White noise σ of ``signal`` from its second differences, or None.

    Parameters
    ----------
    signal : array_like
        A channel sampled regularly [unit], motion and rest alike.
    samples_per_period : float
        Samples in a period of the oscillation the channel holds.

    Returns
    -------
    float or None
        σ [unit]: the median absolute deviation of the second differences, scaled to a
        standard deviation (× 1.4826) and divided by √6. None where the estimate does
        not hold (see the module notes): fewer than :data:`MIN_SAMPLES` samples, the
        signal's second differences beyond :data:`SIGNAL_SHARE` of the noise's, a
        noise not white at the sample's scale, or second differences that are mostly 0.
    """
    s = np.asarray(signal, dtype=float)
    if s.size < MIN_SAMPLES or not samples_per_period > 0:
        return None
    d = np.diff(s, n=2)
    spread = _MAD_SD * _mad(d)
    if not (math.isfinite(spread) and spread > 0.0):
        return None
    largest = float(np.max(np.abs(s - np.median(s))))
    if (2.0 * math.pi / samples_per_period) ** 2 * largest > SIGNAL_SHARE * spread:
        return None
    plus = _mad(d[1:] + d[:-1]) ** 2
    minus = _mad(d[1:] - d[:-1]) ** 2
    if not plus + minus > 0.0:
        return None
    lag_one = (plus - minus) / (plus + minus)
    tolerance = max(WHITENESS_TOLERANCE, WHITENESS_ERRORS * 0.9 / math.sqrt(d.size))
    if abs(lag_one - WHITE_LAG_ONE) > tolerance:
        return None
    return spread / math.sqrt(6.0)
