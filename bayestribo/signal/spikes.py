"""Isolated spikes: single samples a sensor gets wrong (a motion sensor losing its echo).

A spike is one sample (or two in a row) far off the samples around it: the residual
from the running median of five samples, which a smooth oscillation keeps below about
its curvature over a sample, ``A(ωh)²`` (h the sample spacing), and a spike of any
size makes equal to itself. A sample is a spike where its residual exceeds
:data:`SPIKE_FACTOR` times the largest of

* the residuals' robust standard deviation (1.4826 × their median absolute value),
  the noise;
* twice the largest second difference of the running median itself: a smooth
  signal's residual at an extreme is at most its curvature over two samples,
  ``2|s''|h²``. The running median is not quite free of a spike: where the signal moves
  fast, a spike shifts it by one sample's change, ``|s'|h``, which its second
  difference shows at four of five samples about the spike, ``1/(ωh)`` times the
  curvature (50× at 300 samples a period, enough to hide the spike itself). The
  curvature is therefore the largest of the median of |second difference| over
  :data:`CURVATURE_SAMPLES` samples about each sample, which a spike's few samples do
  not move and a smooth signal's curvature, even at 10 samples a period, does not
  lower below about 0.7 of its peak;
* the signal's quantisation step (the smallest non-zero change).

A run of more than :data:`MAX_SPIKE_SAMPLES` flagged samples is not a spike (a shock,
or the release) and is kept.

:func:`find_spikes` finds them; :func:`bridged` returns a copy of the signal in which
each spiked sample is replaced by the median of the five samples about it (one of its
good neighbours' values, so a quantised signal stays on its steps), which
the energy decay (:func:`bayestribo.signal.decay.energy_decay`) analyses instead of the
spikes, saying which samples (times and values) with a :class:`SpikeWarning`. The
recording itself is not changed.
"""

from __future__ import annotations

import numpy as np
import scipy.ndimage
from numpy.typing import ArrayLike, NDArray

from bayestribo.errors import SpikeWarning
from bayestribo.signal.clipping import quantum

__all__ = [
    "CURVATURE_SAMPLES",
    "MAX_SPIKE_SAMPLES",
    "SPIKE_FACTOR",
    "SpikeWarning",
    "bridged",
    "find_spikes",
]

#: Residual, in units of the largest of noise, curvature residual and step, that marks
#: a spike.
SPIKE_FACTOR = 8.0
#: Longest run of flagged samples that counts as a spike.
MAX_SPIKE_SAMPLES = 2
#: Samples over which the running median's second difference is taken as its median:
#: more than twice the samples a spike of :data:`MAX_SPIKE_SAMPLES` shifts (five).
CURVATURE_SAMPLES = 15


def find_spikes(values: ArrayLike) -> NDArray:
    """Indices of the isolated spikes of a signal (see the module notes).

    Parameters
    ----------
    values : array_like
        The signal [any unit], finite.

    Returns
    -------
    ndarray of int
        Sample indices of the spikes, increasing (empty when there are none).
    """
    s = np.asarray(values, dtype=float)
    if s.size < 16:
        return np.zeros(0, dtype=int)
    median = scipy.ndimage.median_filter(s, size=5, mode="nearest")
    residual = np.abs(s - median)
    scale = max(
        1.4826 * float(np.median(residual)),
        2.0 * _curvature(median),
        quantum(s),
    )
    if scale == 0.0:
        return np.zeros(0, dtype=int)
    flagged = residual > SPIKE_FACTOR * scale
    if not flagged.any():
        return np.zeros(0, dtype=int)
    edges = np.flatnonzero(np.diff(np.r_[0, flagged.astype(np.int8), 0]))
    keep = [
        np.arange(a, b)
        for a, b in zip(edges[::2], edges[1::2], strict=True)
        if b - a <= MAX_SPIKE_SAMPLES
    ]
    return np.concatenate(keep) if keep else np.zeros(0, dtype=int)


def _curvature(median: NDArray) -> float:
    """The largest second difference of the running median that a spike cannot make:
    the median of its absolute value over :data:`CURVATURE_SAMPLES` samples, at its
    largest (see the module notes)."""
    d2 = np.abs(np.diff(median, 2))
    if d2.size == 0:
        return 0.0
    size = min(CURVATURE_SAMPLES, d2.size)
    return float(np.max(scipy.ndimage.median_filter(d2, size=size, mode="nearest")))


def bridged(values: NDArray, index: NDArray) -> NDArray:
    """A copy of ``values`` with each sample at ``index`` replaced by the median of the
    five samples about it (a value of its good neighbours, on a quantised signal's
    grid); ``values`` unchanged."""
    out = np.array(values, dtype=float)
    if index.size:
        out[index] = scipy.ndimage.median_filter(out, size=5, mode="nearest")[index]
    return out


def describe(name: str, t: NDArray, values: NDArray, index: NDArray, shown: int = 8) -> str:
    """One sentence naming the channel's spikes: their count, times [s] and values."""
    listed = ", ".join(f"{float(t[i]):.6g} s ({float(values[i]):.6g})" for i in index[:shown])
    more = f" and {index.size - shown} more" if index.size > shown else ""
    return f"{index.size} spike(s) in the {name} at t = {listed}{more}"
