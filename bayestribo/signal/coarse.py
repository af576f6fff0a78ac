"""A coarse digitiser: steps that the noise does not dither.

A channel quantised in steps q (:mod:`bayestribo.signal.quantisation`) whose other
noise is well below a step is rounded the same way wherever the signal passes the
same level: its rounding error is not a white noise of variance q²/12 per sample but
a sawtooth that follows the signal. Two things follow.

* **Its error does not average out over an increment of Π.** Near a turning point
  the signal dwells on one level for a fraction √(2q/A) of a half cycle of swing A,
  and the energy is off by about A × (the rounding there) all that time: the error
  of an increment is about 0.7 q/A of it (5 % at A = 5 q, 10 steps across the swing),
  where the white formula, which lets the errors of the samples cancel, gives a
  hundredth of that at 300 samples a period. :func:`quantised_increments` gives the
  variances from the rounding itself: the channels without their noise, rounded with
  a random placement of the levels (one offset per replicate and channel, uniform
  over a step), integrated like the data. The mean of the rounding error over the
  placement is 0 and that of its square q²/12 for any signal (the levels' placement
  acts as a subtractive dither), so the bias of E is Sheppard's q²/24 per channel.
* **A swing of a few steps is not resolved.** Below a step of amplitude the rounded
  signal says little about the true one (below half a step it reads as rest), so a
  motion that sticks at an amplitude of a few µm seems to stop cycles early on a
  coarse velocity channel, and the turning points of the smallest swings are not
  found at all: the end of motion is not observed.
  :func:`resolved_turning_points` counts the turning points up to the last whose
  amplitude is at least :data:`RESOLVED_STEPS` steps in each coarse channel (ω_d|Y_n|
  for the velocity); the analysis ends at the turning point after it (the half
  cycle down to it starts resolved; :func:`bayestribo.signal.decay.energy_decay`),
  and Π is truncated there like a record that ends in motion (or later, at the last
  sample a coarse channel reaches a step from its zero, where the turning points of
  the smaller swings went unfound: :func:`resolved_end`). Where the rounding is left
  to the variances above, one
  step is enough: on the paper's rig rounded to a tenth of its swing with the levels
  placed at random, the 95 % intervals of ζ and μ_k covered 6 runs in 6 (sd(z) 0.8),
  where ending the motion at the velocity's last reading off its rest put μ_k ten
  posterior standard deviations off.

**A record whose swings sink below two steps within three oscillations** still holds
a decay: its first swings stand out of the rounding and shrink from one turning point
to the next. :func:`coarse_window` lets such a record be analysed on as few as
:data:`MIN_COARSE_TURNING_POINTS` turning points (two oscillations; the first
oscillation too, when the one skipped after the release is what it lacks), where a
record dithered by its noise needs three oscillations: the intervals are wide (ζ and
μ_k are told apart by the shape of a longer decay) and come with a
:class:`~bayestribo.errors.CoarseSignalWarning`. On the paper's rig at 3 steps across
the swing (``benchmarks/coarse_placements.py``) 9 placements of 20 were refused for
lacking one to three turning points; on two oscillations each was covered.

A channel is coarse (:func:`coarse_steps`) when it is quantised and the noise measured
at rest is at most :data:`DITHER_STEPS` steps (a rest on one level shows none; the
measured level is floored at q/√12). A finer quantiser (a vibrometer's resolution, the
AppStat2020 files' three decimals) is dithered by the noise: the white formula holds.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "DITHER_STEPS",
    "MIN_COARSE_TURNING_POINTS",
    "MIN_SWING_STEPS",
    "RESOLVED_STEPS",
    "CoarseWindow",
    "coarse_steps",
    "coarse_window",
    "few_steps_note",
    "quantised_increments",
    "resolved_end",
    "resolved_turning_points",
    "swing_end",
]

#: Noise at rest, in steps, up to which a quantised channel is coarse (not dithered).
DITHER_STEPS = 0.5
#: Amplitude, in steps of a coarse channel, a turning point needs to be resolved.
RESOLVED_STEPS = 1.0
#: Fewest steps across a coarse channel's swing at which the rounding's variances hold:
#: on the paper's rig (``benchmarks/coarse_placements.py``, 20 placements a count) 4 and 5
#: steps covered ζ and μ_k in 20 of 20 fits; 3 steps covered both in 20 of 20 (z of μ_k
#: +1.1 in each: wide intervals whose centres are off alike), and an earlier version
#: missed ζ in 2 of 11 (z -2.7, -3.6).
MIN_SWING_STEPS = 4
#: Fewest turning points a coarse record is analysed on when its swings sink below two
#: steps within three oscillations (two oscillations: the total decay is measured, its
#: split between ζ and μ_k is left wide).
MIN_COARSE_TURNING_POINTS = 4
#: Monte Carlo replicates drawn at once (memory: block × samples floats).
_BLOCK = 50


@dataclass(frozen=True)
class CoarseWindow:
    """The turning points a coarse record is analysed on (:func:`coarse_window`).

    Parameters
    ----------
    skip : int
        Turning points skipped before the analysis.
    least : int
        Fewest turning points needed after them.
    note : str or None
        What was changed from the requested analysis, in words (None: nothing).
    """

    skip: int
    least: int
    note: str | None = None


def coarse_window(
    found: int,
    resolved: Callable[[int], int],
    skip: int,
    least: int,
    *,
    keep_skip: bool = False,
) -> CoarseWindow:
    """The skip and least count of turning points for a coarse record that lacks some.

    A coarse record whose swings sink below two steps before ``skip + least`` turning
    points (the turning points of smaller swings are the rounding's) is analysed on
    :data:`MIN_COARSE_TURNING_POINTS`, and with the skipped turning points too when
    only they are missing.

    Parameters
    ----------
    found : int
        Turning points found after the release.
    resolved : callable
        ``resolved(s)``: how many of the turning points from ``s`` on the analysis keeps
        (those the coarse channels resolve, and the one after the last of them).
    skip : int
        Turning points the analysis was asked to skip (the release's oscillation).
    least : int
        Turning points it was asked to keep at least, after them.
    keep_skip : bool
        Never analyse the skipped turning points (they were left out for a reason of
        their own: clipped, irregular, or skipped by count on request).

    Returns
    -------
    CoarseWindow
        ``skip`` and ``least`` unchanged (note None) when the record has enough or too
        few even so (the caller refuses it).

    Examples
    --------
    >>> coarse_window(5, lambda s: 5 - s, 1, 6).note
    '4 turning points after the skipped ones, where 6 are asked for'
    >>> coarse_window(4, lambda s: 4 - s, 1, 6).skip
    0
    >>> coarse_window(9, lambda s: 9 - s, 1, 6).note is None
    True
    """

    def enough(s: int, n: int) -> bool:
        return found - s >= n and resolved(s) >= n

    if enough(skip, least):
        return CoarseWindow(skip, least)
    fewest = min(least, MIN_COARSE_TURNING_POINTS)
    asked = f"{fewest} turning points after the skipped ones, where {least} are asked for"
    if enough(skip, fewest):
        return CoarseWindow(skip, fewest, asked)
    if skip > 0 and not keep_skip and enough(0, fewest):
        return CoarseWindow(
            0,
            fewest,
            f"{fewest} turning points from the first one after the release on ("
            + ("the one" if skip == 1 else f"the {skip}")
            + " skipped after the release analysed too)",
        )
    return CoarseWindow(skip, least)


def coarse_steps(
    steps: tuple[float | None, float | None], levels: tuple[float | None, float | None]
) -> tuple[float | None, float | None]:
    """The steps of the channels quantised coarsely (not dithered by their noise).

    Parameters
    ----------
    steps : (float or None, float or None)
        Quantisation steps of the displacement [length unit] and the velocity
        [length unit/s] (None: not quantised).
    levels : (float or None, float or None)
        Their noise measured at rest, same units (None: not measured).

    Returns
    -------
    (float or None, float or None)
        Each step where the channel's noise is at most :data:`DITHER_STEPS` of it,
        else None.

    Examples
    --------
    >>> coarse_steps((1e-3, 1e-3), (0.29e-3, 2e-3))
    (0.001, None)
    """
    out: list[float | None] = []
    for step, level in zip(steps, levels, strict=True):
        coarse = step is not None and step > 0 and (level is None or level <= DITHER_STEPS * step)
        out.append(float(step) if coarse else None)  # type: ignore[arg-type]
    return out[0], out[1]


def few_steps_note(
    channels: tuple[ArrayLike | None, ArrayLike | None],
    steps: tuple[float | None, float | None],
) -> str | None:
    """Which coarse channels hold fewer than :data:`MIN_SWING_STEPS` steps across their
    swing, said in words; None when none does.

    Parameters
    ----------
    channels : (array_like or None, array_like or None)
        The recorded displacement [length unit] and velocity [length unit/s] over the
        motion (None: not recorded).
    steps : (float or None, float or None)
        Their coarse steps (:func:`coarse_steps`), same units.

    Returns
    -------
    str or None
        E.g. ``"the displacement holds 3 steps of 0.00128 across its swing"``.

    Examples
    --------
    >>> few_steps_note(([0.0, 3.0, -0.0, 1.0], None), (1.0, None))
    'the displacement holds 3 steps of 1 across its swing'
    >>> few_steps_note(([0.0, 5.0, 1.0], None), (1.0, None)) is None
    True
    """
    said = []
    for name, signal, step in zip(("displacement", "velocity"), channels, steps, strict=True):
        if signal is None or step is None:
            continue
        values = np.asarray(signal, dtype=float)
        if values.size == 0:
            continue
        # a rounded range is a whole number of steps: half a step of margin
        across = float(np.ptp(values)) / step
        if across < MIN_SWING_STEPS - 0.5:
            said.append(f"the {name} holds {across:.0f} steps of {step:.3g} across its swing")
    return "; ".join(said) or None


def resolved_turning_points(
    values: ArrayLike, omega_d: float, steps: tuple[float | None, float | None]
) -> int:
    """How many of the leading turning points have a swing the coarse channels resolve.

    Parameters
    ----------
    values : array_like
        Turning-point values of the displacement about the equilibrium [length unit],
        in time order.
    omega_d : float
        Angular frequency of the oscillation [rad/s]: the velocity's swing is ω_d|Y_n|.
    steps : (float or None, float or None)
        Steps of the coarse displacement and velocity (:func:`coarse_steps`).

    Returns
    -------
    int
        The count of turning points up to the last whose amplitude is at least
        :data:`RESOLVED_STEPS` steps in each coarse channel (the rounded values scatter
        by half a step about a decay: one low reading does not end it), 0 when none is.

    Examples
    --------
    >>> resolved_turning_points([5.0, -4.0, 3.0, -0.9, 1.0, -0.5], 1.0, (1.0, None))
    5
    """
    amp = np.abs(np.asarray(values, dtype=float))
    ok = np.ones(amp.size, dtype=bool)
    step_x, step_v = steps
    if step_x is not None:
        ok &= amp >= RESOLVED_STEPS * step_x
    if step_v is not None:
        ok &= float(omega_d) * amp >= RESOLVED_STEPS * step_v
    good = np.flatnonzero(ok)
    return int(0 if good.size == 0 else good[-1] + 1)


def swing_end(signal: ArrayLike, step: float, period_samples: float, steps: float) -> int | None:
    """The sample after which a coarse channel's swing stays below ``steps`` steps.

    The swing is the range of the channel over one period about each sample (2ω|Y| for
    the velocity). A velocity recorded alone is integrated into the displacement, and
    where its swing is a step or two the integral's turning points are the rounding's:
    its mean over a cycle, a good part of a step, changes with the swing and the
    integral wanders by far more than the swing.

    Parameters
    ----------
    signal : array_like
        The channel [signal unit].
    step : float
        Its coarse step [signal unit].
    period_samples : float
        Samples per period of the oscillation.
    steps : float
        Swing, in steps, below which the channel no longer resolves the motion.

    Returns
    -------
    int or None
        One past the last sample whose period holds a swing of at least ``steps``
        steps; None when there is no such sample, or when the swing holds to the end.

    Examples
    --------
    >>> import numpy as np
    >>> v = np.round(np.exp(-np.arange(400) / 100.0) * 4 * np.sin(np.arange(400) / 3.0))
    >>> swing_end(v, 1.0, 6 * np.pi, 4.0)
    91
    """
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    values = np.asarray(signal, dtype=float)
    if not (step > 0 and period_samples > 0) or values.size == 0:
        raise ValueError(
            f"step, period_samples: expected positive numbers, got {step!r}, {period_samples!r}"
        )
    size = max(round(period_samples), 1)
    swing = maximum_filter1d(values, size) - minimum_filter1d(values, size)
    wide = np.flatnonzero(swing >= (steps - 0.5) * step)
    if wide.size == 0 or wide[-1] == values.size - 1:
        return None
    return int(wide[-1]) + 1


def resolved_end(
    channels: tuple[NDArray | None, NDArray | None],
    steps: tuple[float | None, float | None],
    start: int,
) -> int:
    """The last sample, from ``start`` on, at which every coarse channel has still
    reached :data:`RESOLVED_STEPS` steps from its zero.

    Parameters
    ----------
    channels : (ndarray or None, ndarray or None)
        The displacement about its equilibrium and the velocity [signal units].
    steps : (float or None, float or None)
        Steps of the coarse channels (:func:`coarse_steps`; None: not coarse).
    start : int
        The first sample that may be the end (the last resolved turning point).

    Returns
    -------
    int
        The smallest over the coarse channels of the last sample where the channel's
        magnitude is at least :data:`RESOLVED_STEPS` steps; ``start`` when one has none
        after it.

    Examples
    --------
    >>> import numpy as np
    >>> resolved_end((np.array([3.0, -2.0, 1.5, -0.5, 0.2]), None), (1.0, None), 1)
    2
    """
    end: int | None = None
    for signal, step in zip(channels, steps, strict=True):
        if step is None or signal is None:
            continue
        far = np.flatnonzero(
            np.abs(np.asarray(signal[start:], dtype=float)) >= RESOLVED_STEPS * step
        )
        last = start + (int(far[-1]) if far.size else 0)
        end = last if end is None else min(end, last)
    return start if end is None else end


def quantised_increments(
    y: NDArray,
    yp: NDArray,
    edges: NDArray,
    weights: list[NDArray],
    steps: tuple[float | None, float | None],
    other_sd: tuple[float, float] = (0.0, 0.0),
    *,
    n_replicates: int = 300,
    seed: int = 0,
) -> tuple[NDArray, NDArray, NDArray]:
    """Bias, variance and neighbour covariance of the increments of E = (y² + y'²)/2
    that a coarse quantiser's rounding gives (see the module notes).

    Parameters
    ----------
    y, yp : ndarray
        The channels without their noise (dimensionless), on the decay's samples.
    edges, weights : ndarray, list of ndarray
        The increments' sample edges and quadrature weights
        (:func:`bayestribo.signal.increments.increment_weights`).
    steps : (float or None, float or None)
        Steps of the coarse channels in units of y and y' (None: the channel is not
        coarse and its noise is left to the white formula).
    other_sd : (float, float)
        Standard deviation of the rest of the noise of each coarse channel (units of y,
        y'), drawn white before the rounding.
    n_replicates : int
        Placements of the levels drawn (relative error of a variance about
        √(2/n_replicates)).
    seed : int
        Seed of the draws.

    Returns
    -------
    bias : ndarray
        Mean added to each increment: Sheppard's q²/24 per coarse channel (plus half
        the other noise's variance) times the increment's summed weights.
    variance : ndarray
        Variance of each increment over the placements and the other noise.
    neighbour_cov : ndarray
        Covariance of each pair of neighbouring increments (length ``edges.size - 2``).
    """
    if n_replicates < 2:
        raise ValueError(f"n_replicates: expected at least 2, got {n_replicates}")
    rng = np.random.default_rng(seed)
    m = edges.size - 1
    clean = _integrated(0.5 * (y * y + yp * yp), edges, weights)
    draws = np.empty((n_replicates, m))
    done = 0
    while done < n_replicates:
        k = min(_BLOCK, n_replicates - done)
        energy = np.zeros((k, y.size))
        for signal, step, sd in zip((y, yp), steps, other_sd, strict=True):
            if step is None:
                energy += signal * signal
                continue
            offset = rng.uniform(-0.5, 0.5, (k, 1)) * step
            noisy = signal + offset
            if sd > 0:
                noisy = noisy + sd * rng.standard_normal((k, y.size))
            rounded = np.round(noisy / step) * step - offset
            energy += rounded * rounded
        energy *= 0.5
        draws[done : done + k] = _integrated(energy, edges, weights)
        done += k
    sums = np.array([float(np.sum(w)) for w in weights])
    bias = sum(
        (step * step / 12.0 + sd * sd) * sums
        for step, sd in zip(steps, other_sd, strict=True)
        if step is not None
    )
    bias = 0.5 * np.asarray(bias, dtype=float) * np.ones(m)
    dev = draws - (clean + bias)
    # the mean is known exactly (the placement is a subtractive dither): deviations
    # about it, not about the replicates' mean
    variance = np.mean(dev * dev, axis=0)
    neighbours = np.mean(dev[:, :-1] * dev[:, 1:], axis=0) if m > 1 else np.zeros(0)
    return bias, variance, neighbours


def _integrated(values: NDArray, edges: NDArray, weights: list[NDArray]) -> NDArray:
    """∫ values over each increment, as :func:`bayestribo.signal.increments.
    integrate_increments` takes them (values of shape (..., samples))."""
    return np.stack(
        [
            values[..., a : b + 1] @ w
            for a, b, w in zip(edges[:-1], edges[1:], weights, strict=True)
        ],
        axis=-1,
    )
