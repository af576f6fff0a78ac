"""The digitiser's step: a channel recorded (or written) in multiples of a step q.

A channel quantised in steps q carries a rounding error spread uniformly over one
step, of standard deviation q/√12, on every sample: a noise the rest segments may not
show (a signal at rest sits on one level, and its measured noise is then 0) and the
data sheet's resolution may not state (a 12-bit digitiser, or a file written with few
decimals: the AppStat2020 recordings hold three). The noise model
(:mod:`bayestribo.signal.noise`) therefore uses at least q/√12 for a quantised
channel.

The step is found from the sample-to-sample changes: the smallest non-zero change, or
a whole fraction of it (down to a tenth), is the candidate, and the channel is
quantised when nearly all changes are whole multiples of it. A channel of continuous
values (any real noise above the printing precision) fails the test: its changes are
not multiples of the smallest one.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "FINE_DITHER_STEPS",
    "QUANTISATION_NOISE_FACTOR",
    "finely_dithered",
    "quantisation_step",
    "still_on_its_steps",
]

#: Standard deviation of the rounding error per step: 1/√12.
QUANTISATION_NOISE_FACTOR = 1.0 / math.sqrt(12.0)
#: Noise, in steps, from which a quantised channel's levels are dithered finely: its
#: rounding adds at most 1/192 of the noise's variance, and the levels tell nothing of
#: the motion the signal itself does not (a file written with five decimals of metres,
#: 10 µm steps under 0.2 mm of noise).
FINE_DITHER_STEPS = 4.0
#: Changes needed to call a step.
_MIN_CHANGES = 20
#: Changes below this fraction of a channel's largest magnitude are floating-point dust.
_DUST = 1e-12
#: Fraction of the changes that must be whole multiples of the step.
_WHOLE_FRACTION = 0.99
#: How far from a whole multiple a change may be (rounding of the decimal text).
_TOLERANCE = 1e-3
#: How far from a whole multiple a change may be to be assigned it while the step is
#: refined (:func:`_refined`).
_ASSIGN = 0.25
#: The smallest change may be up to this many steps.
_MAX_DIVISOR = 10


def quantisation_step(values: ArrayLike) -> float | None:
    """The step a channel's values are multiples of, or None when they are not quantised.

    Parameters
    ----------
    values : array_like
        The channel's samples (finite).

    Returns
    -------
    float or None
        The step q [signal unit], when at least 99 % of the non-zero sample-to-sample
        changes (at least 20 of them) are within 1e-3 of whole multiples of the smallest
        one or of a whole fraction of it (1/2 ... 1/10, the largest that holds); None
        otherwise.

    Examples
    --------
    >>> import numpy as np
    >>> quantisation_step(np.round(np.sin(np.arange(100) / 5.0), 3))
    0.001
    >>> quantisation_step(np.sin(np.arange(100) / 5.0)) is None
    True
    """
    x = np.asarray(values, dtype=float)
    if not np.isfinite(x).all():
        x = x[np.isfinite(x)]
    if x.size < 2:
        return None
    change = np.diff(x)
    np.abs(change, out=change)
    # changes at the floating point's resolution are no step (the means of a binned
    # record's samples differ by such dust where their sums are equal)
    change = change[change > _DUST * float(np.max(np.abs(x)))]
    if change.size < _MIN_CHANGES:
        return None
    smallest = float(change.min())
    # a step that misses more than this many changes fails (checked on a first part of
    # the changes before all of them: an unquantised 1 MHz record fails on its first
    # 2 %, ten times over)
    allowed = (1.0 - _WHOLE_FRACTION) * change.size
    head = change[: min(change.size, 2 * math.ceil(allowed) + 100)]
    # the smallest change may be several steps (no sample moved by one): try its
    # whole fractions, largest step first
    for k in range(1, _MAX_DIVISOR + 1):
        # the smallest change carries the decimal text's rounding, which a change of
        # many steps multiplies (a 12-bit step of 0.9765625 µm written in mm with six
        # decimals, 160 steps a sample): the step is refined from the changes of a few
        # steps first, then of more, before the changes are judged against it
        step = _refined(head, smallest / k, allowed)
        if step is None:
            continue
        missed = np.count_nonzero(np.abs(head / step - np.round(head / step)) > _TOLERANCE)
        if missed > allowed + 1:
            continue
        step = _refined(change, step, allowed)
        if step is None:
            continue
        ratio = change / step
        whole = np.abs(ratio - np.round(ratio)) <= _TOLERANCE
        if np.mean(whole) >= _WHOLE_FRACTION:
            # refined from every change (the smallest carries the decimal text's rounding)
            n = np.round(ratio)
            return float(round(float(np.sum(change) / np.sum(n)), 15))
    return None


def _refined(change: np.ndarray, step: float, allowed: float) -> float | None:
    """``step`` refined from the changes of at most 4, 16, 64, ... steps in turn (each
    the sum of the changes over the sum of their whole multiples), or None where more
    than ``allowed`` + 1 of those changes are not within a quarter step of a whole
    multiple of it (no multiple to assign them; whether the changes are whole
    multiples within :data:`_TOLERANCE` is judged after, against the refined step)."""
    limit = 4.0
    while True:
        ratio = change / step
        near = ratio <= limit + 0.5
        n = np.round(ratio[near])
        if np.count_nonzero(np.abs(ratio[near] - n) > _ASSIGN) > allowed + 1:
            return None
        total = float(np.sum(n))
        if total > 0:
            step = float(np.sum(change[near])) / total
        if near.all():
            return step
        limit *= 4.0


def finely_dithered(values: ArrayLike, step: float | None) -> bool:
    """Whether a channel quantised in ``step`` carries a noise of
    :data:`FINE_DITHER_STEPS` steps or more: its levels are then those of a continuous
    signal, not a coarse digitiser's.

    The noise is the white noise of the fourth differences, 1.4826 MAD(Δ⁴x)/√70 (the
    motion's share is below 1 % of its amplitude at 20 samples a period), over the
    whole channel.

    Parameters
    ----------
    values : array_like
        The channel's samples.
    step : float or None
        Its step (:func:`quantisation_step`); None: not quantised (False).

    Returns
    -------
    bool

    Examples
    --------
    >>> import numpy as np
    >>> noisy = np.random.default_rng(0).normal(0.0, 2e-4, 2000)
    >>> finely_dithered(np.round(noisy, 5), 1e-5), finely_dithered(np.round(noisy, 3), 1e-3)
    (True, False)
    """
    if step is None or not step > 0:
        return False
    x = np.asarray(values, dtype=float)
    d4 = np.diff(x[np.isfinite(x)], n=4)
    if d4.size == 0:
        return False
    noise = 1.4826 * float(np.median(np.abs(d4 - np.median(d4)))) / math.sqrt(70.0)
    return noise >= FINE_DITHER_STEPS * step


def still_on_its_steps(rests: list[ArrayLike], step: float | None) -> bool:
    """True when the rests of a quantised channel hold (nearly) no noise: a signal at
    rest on one level, or toggling between two now and then.

    Such rests measure the rounding of a still signal, not the noise of the moving one
    (whose rounding error, spread over the step, is white at q/√12): their spectrum,
    near zero, would make the increments' noise vanish.

    Parameters
    ----------
    rests : list of array_like
        The channel's samples in each rest [signal unit].
    step : float or None
        The channel's quantisation step q (:func:`quantisation_step`); None: not
        quantised, and the rests are never called still.

    Returns
    -------
    bool
        True when the rests' variance about each one's mean is under a quarter of the
        rounding's, q²/48.
    """
    if step is None or not step > 0:
        return False
    parts = [np.asarray(r, dtype=float) for r in rests]
    parts = [r for r in parts if r.size]
    if not parts:
        return False
    squares = sum(float(np.sum((r - r.mean()) ** 2)) for r in parts)
    count = sum(r.size for r in parts)
    return squares / count < 0.25 * step * step / 12.0
