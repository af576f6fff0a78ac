"""A record sampled far faster than its noise allows to read: averaged in bins.

The turning points are found on the raw samples, each standing ten noise standard
deviations out (:func:`bayestribo.signal.peaks.find_peaks`), and the motion is told
from rest by a velocity derived over an eighth of a period
(:func:`bayestribo.signal.motion.motion_span`). A record whose swings are a few times
its noise per sample, but whose period holds many samples (a seismometer at 10 Hz
with an 8.9 s period: 89 samples a period, swings of 0.05-0.2 V under 0.005-0.014 V of
noise), holds its oscillation plainly over a period and none of it at one sample: it
was refused ("found 0 usable extrema", "no motion found").

Averaging the samples in consecutive bins of ``k`` keeps the noise model exact: the
means of white noise over disjoint bins are white, of standard deviation σ/√k, and
the analysis measures that noise from the binned record as from any other. The
oscillation passes the bin with the gain ``sin(πkf/fs) / (k sin(πf/fs))`` at its
frequency f, which :func:`binned` divides out (3e-3 for four samples at 89 a period);
the bins' centres are the new time stamps, regular at ``k`` steps. The bin is the
largest that leaves :data:`BINNED_PERIOD_SAMPLES` samples a period (the turning
points' parabola over ±1/12 period still holds a sample on each side) and
:data:`MIN_BINNED_SAMPLES` samples in all. The motion is told from rest on a velocity
derived from the displacement, whose noise a bin of ``k`` lowers by about k^1.5 against
the oscillation's velocity (σ/√k over a step k times longer): on simulated records of 6
cycles at 91 samples a period under noise 7 % of the first amplitude, bins leaving 20
samples a period answered 5 of 20 and bins leaving 12 answered 16
(``benchmarks/binned_records.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bayestribo.errors import BayestriboError, BinnedRecordWarning

__all__ = [
    "BINNED_PERIOD_SAMPLES",
    "MIN_BINNED_SAMPLES",
    "BinnedRecordWarning",
    "Bins",
    "bin_size",
    "binned",
]

#: Samples a period that a binned record keeps at least.
BINNED_PERIOD_SAMPLES = 12
#: Samples a binned record keeps at least (a decay analysis reads no fewer).
MIN_BINNED_SAMPLES = 64


@dataclass(frozen=True)
class Bins:
    """How a record was binned.

    Parameters
    ----------
    size : int
        Samples averaged in each bin.
    period_samples : float
        Samples a period in the raw record.
    gain : float
        Gain of the bin's mean at the oscillation's frequency (divided out).
    """

    size: int
    period_samples: float
    gain: float


def bin_size(period_samples: float, n: int) -> int | None:
    """The bin for a record of ``n`` samples with ``period_samples`` a period.

    Returns
    -------
    int or None
        The largest ``k`` ≥ 2 leaving :data:`BINNED_PERIOD_SAMPLES` samples a period
        and :data:`MIN_BINNED_SAMPLES` samples in all; ``None`` where no such bin is
        (the period holds fewer than twice :data:`BINNED_PERIOD_SAMPLES`).
    """
    if not (math.isfinite(period_samples) and period_samples > 0) or n <= 0:
        return None
    k = min(int(period_samples // BINNED_PERIOD_SAMPLES), n // MIN_BINNED_SAMPLES)
    return k if k >= 2 else None


def bin_gain(size: int, period_samples: float) -> float:
    """Gain of a mean over ``size`` consecutive samples on a sinusoid of
    ``period_samples`` samples a period (1 at a constant)."""
    phase = math.pi / period_samples
    return math.sin(size * phase) / (size * math.sin(phase))


def binned(
    t: NDArray, channels: tuple[NDArray | None, ...], size: int, period_samples: float
) -> tuple[NDArray, tuple[NDArray | None, ...], Bins]:
    """The record averaged in consecutive bins of ``size`` samples.

    Parameters
    ----------
    t : ndarray
        Regular time stamps [s].
    channels : tuple of ndarray or None
        The signals [their units], each of the shape of ``t`` (``None`` passed on).
    size : int
        Samples a bin (≥ 2); the last samples that fill no bin are left out.
    period_samples : float
        Samples a period of the oscillation (sets the gain divided out).

    Returns
    -------
    t : ndarray
        The bins' mean times [s].
    channels : tuple of ndarray or None
        The bins' means divided by the gain at the oscillation's frequency.
    bins : Bins
    """
    if size < 2:
        raise BayestriboError(f"a bin holds at least 2 samples, got {size}")
    m = (t.size // size) * size
    gain = bin_gain(size, period_samples)

    def mean(s: NDArray) -> NDArray:
        return np.asarray(s[:m], dtype=float).reshape(-1, size).mean(axis=1)

    out = tuple(None if s is None else mean(s) / gain for s in channels)
    return mean(t), out, Bins(size, float(period_samples), gain)
