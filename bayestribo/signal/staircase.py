r"""Turning points of a coarse displacement from the time its staircase spends above a level.

A displacement rounded to steps q that its noise does not dither
(:mod:`bayestribo.signal.coarse`) reads, at each turning point, the level nearest the
extreme: its turning points sit on a few levels, each up to q/2 from the true one,
and many successive turning points on the same level. The energy lost in a half cycle,
``Y_n² − Y_n+1²``, is then zero for most half cycles and a whole step's worth for a few:
the law-free ΔE(A) read off them (:func:`~bayestribo.inference.dissipation.
turning_point_dissipation`) came out negative, or several times the truth, on simulated
records of 3 to 5 steps across the swing (``benchmarks/coarse_dissipation.py``).

The staircase still says where the extreme is: near a turning point of swing A about
the equilibrium c the motion is ``c + A cos ω(t − t_n)`` (to second order in the
damping: the first-order asymmetry of the two sides cancels in their sum), and it is
above a boundary b between two levels (``(L + L')/2``, known exactly from the levels)
for a time D with ``b − c = A cos(ωD/2)``. D is the number of samples above b times the
sample step: exact to a sample without noise, and unbiased to first order with a noise
below a step (each crossing's noise moves samples across b in both directions alike).
Near the turning point the time above the boundaries says how wide the arc is at each
level, and so both the swing and the equilibrium: ``b = c + A cos(ωD/2)`` is a straight
line in ``cos(ωD/2)`` whose slope is A. Every boundary the arc crosses between its two
neighbouring turning points gives one such equation (in the turning point's frame,
minima turned over), with the equilibrium ``c0 + c1 t`` shared by all turning points:
one linear least-squares fit gives the equilibrium and every A at once (a swing of a
step or two crosses one or two boundaries, and leans on the others for c). Its error is
that of D, ``A sin(ωD/2) ω δD/2`` in b: a few thousandths of a step at 300 samples a
period, where the level itself is off by up to half a step.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.signal.coarse import coarse_steps

__all__ = [
    "LARGEST_MODEL_ERROR",
    "NOISE_CLEARANCE",
    "coarse_turning_points",
    "staircase_turning_points",
]

#: A boundary is used when it lies this many noise sd inside the arc at least, from its
#: top level and from the lower of its neighbouring turning points' levels (a level the
#: motion only grazes is crossed by the noise alone, and its time above is biased).
NOISE_CLEARANCE = 2.0
#: Relative error of the cosine model of an arc, beside the damping's second order.
_MODEL_ERROR = 1e-3
#: Largest second-order error of the cosine model, as a fraction of the swing, of the
#: best boundary of a turning point kept at either end of the run.
LARGEST_MODEL_ERROR = 0.01


def _boundaries(
    t: NDArray,
    s: NDArray,
    lo: float,
    hi: float,
    sign: float,
    step: float,
    omega: float,
    noise: float,
) -> tuple[NDArray, NDArray, NDArray]:
    """Boundaries (in the frame ``sign × s``) the arc over [lo, hi] crosses, the cosine
    of the half angle of each, and the sd of one sample's time [s] at them."""
    w = (t >= lo) & (t <= hi)
    empty = np.empty(0)
    if w.sum() < 3 or lo < t[0] or hi > t[-1]:  # an arc the record does not hold whole
        return empty, empty, empty
    z = sign * s[w]
    dt = float(np.median(np.diff(t[w])))
    # the boundaries above the shallower of the two neighbouring extremes: the arc leaves
    # each of them on both sides within the window
    centre = int(np.argmax(z))
    if centre == 0 or centre == z.size - 1:
        return empty, empty, empty
    top = float(z[centre])
    bottom = max(float(np.min(z[:centre])), float(np.min(z[centre:])))
    clear = NOISE_CLEARANCE * noise - 1e-6 * step  # (levels read back within rounding)
    b = top - (np.arange(round((top - bottom) / step) + 1) + 0.5) * step
    b = b[(b <= top - 0.5 * step - clear) & (b >= bottom + 0.5 * step + clear)]
    if b.size == 0:
        return empty, empty, empty
    above = (z[None, :] > b[:, None]).sum(axis=1)
    half = 0.5 * omega * dt * above
    ok = (above > 0) & (half < math.pi)
    return b[ok], np.cos(half[ok]), np.full(int(ok.sum()), dt)


def staircase_turning_points(
    t: ArrayLike,
    displacement: ArrayLike,
    times: ArrayLike,
    signs: ArrayLike,
    step: float,
    omega: float,
    *,
    noise: float = 0.0,
    fit_drift: bool = False,
) -> tuple[NDArray, float, float] | None:
    """Turning points of a coarse displacement from the time it spends above its levels.

    Parameters
    ----------
    t : array_like
        Sample times [s].
    displacement : array_like
        The recorded displacement, rounded to ``step`` [length unit].
    times : array_like
        Times of the turning points [s], in order (from the staircase's extremes).
    signs : array_like
        +1 for a maximum, −1 for a minimum, one per turning point.
    step : float
        The quantisation step [length unit].
    omega : float
        Angular frequency of the oscillation [rad/s] (the damped one).
    noise : float
        Noise sd of the displacement at rest [length unit] (0: none).
    fit_drift : bool
        Fit a linear drift of the equilibrium too.

    Returns
    -------
    (values, offset, drift) or None
        The turning points about the equilibrium [length unit] (NaN outside the longest
        run of those whose arc crosses a boundary the noise leaves clear, and for a
        swing at either end of it left to the cosine model's second order), the
        equilibrium at t = 0 [length unit] and its drift [length unit/s]; None when no
        arc crosses a boundary, or the fit is not determined.
    """
    t = np.asarray(t, dtype=float)
    s = np.asarray(displacement, dtype=float)
    tn = np.asarray(times, dtype=float)
    sg = np.sign(np.asarray(signs, dtype=float))
    n = tn.size
    if n < 2 or not (step > 0 and omega > 0) or np.any(sg == 0):
        return None
    half_period = math.pi / omega
    edges = np.concatenate([[tn[0] - half_period], tn, [tn[-1] + half_period]])
    found = [_boundaries(t, s, edges[j], edges[j + 2], sg[j], step, omega, noise) for j in range(n)]
    crossed = np.array([f[0].size > 0 for f in found])
    if not crossed.any():
        return None
    # the longest run of turning points whose arcs cross a boundary (the smallest swings,
    # in the noise's reach, may cross none here and there: those after the first such
    # gap are left out, as the resolved swings end a coarse record's analysis)
    edges_of_runs = np.flatnonzero(np.diff(np.concatenate([[0], crossed.astype(int), [0]])))
    starts, stops = edges_of_runs[::2], edges_of_runs[1::2]
    longest = int(np.argmax(stops - starts))
    first, last = int(starts[longest]), int(stops[longest])
    keep = np.arange(first, last)
    m = keep.size
    cols = (2 if fit_drift else 1) + m
    t0 = float(tn[first])
    rows, target, timing_sd, owner = [], [], [], []
    for i, j in enumerate(keep):
        b, cos, dt = found[j]
        # the boundary in the turning point's frame: sign × c(t_n) + A_n cos(ωD/2)
        block = np.zeros((b.size, cols))
        block[:, 0] = sg[j]
        if fit_drift:
            block[:, 1] = sg[j] * (tn[j] - t0)
        block[:, cols - m + i] = cos
        rows.append(block)
        target.append(b)
        # the time above: a sample's rounding at each end, and the noise's at each crossing
        sin = np.sqrt(np.clip(1.0 - cos * cos, 0.0, None))
        guess = 0.5 * float(np.ptp(b)) + step
        slope = guess * omega * sin
        timing = dt * dt / 6.0 + 0.56 * noise * dt / np.maximum(slope, 1e-300)
        timing_sd.append(0.5 * slope * np.sqrt(timing))
        owner.append(np.full(b.size, i))
    design, y = np.vstack(rows), np.concatenate(target)
    timing_sd, owner = np.concatenate(timing_sd), np.concatenate(owner)
    if y.size <= cols:
        return None
    amp = np.full(m, step)
    decrement = np.zeros(m)
    for _ in range(3):
        # the cosine model's error: 1e-3 of the swing, and the second order of the damping:
        # the arcs on the two sides differ by the half cycle's loss of swing d, which
        # their sum cancels to first order only; the rest is about (d/2)² (1 − cos)/(1 + cos)
        # of the swing (for Coulomb friction, exactly so within a factor 2 from the top of
        # the arc to near the bottom): the boundaries below the equilibrium weigh less
        cos_all = design[np.arange(y.size), cols - m + owner]
        second = (0.5 * decrement[owner]) ** 2 * (1.0 - cos_all) / np.maximum(1.0 + cos_all, 0.02)
        model = amp[owner] * (_MODEL_ERROR + second)
        w = 1.0 / np.hypot(timing_sd, model)
        coef, _, rank, _ = np.linalg.lstsq(design * w[:, None], y * w, rcond=None)
        if rank < cols:
            return None
        amp = coef[cols - m :]
        if not np.all(np.isfinite(amp) & (amp > 0)):
            return None
        if m >= 2:
            decrement = np.abs(np.gradient(amp)) / amp
    # a swing at either end whose best boundary leaves more than LARGEST_MODEL_ERROR of it
    # to the second order (a swing of a step or two losing a third of itself in a half
    # cycle) is left out, as one that crosses no boundary is
    best = np.full(m, np.inf)
    np.minimum.at(best, owner, second)
    good = best <= LARGEST_MODEL_ERROR
    if not good.any():
        return None
    lo, hi = int(np.argmax(good)), m - int(np.argmax(good[::-1]))
    values = np.full(n, np.nan)
    values[keep[lo:hi]] = sg[keep[lo:hi]] * amp[lo:hi]
    c1 = float(coef[1]) if fit_drift else 0.0
    return values, float(coef[0]) - c1 * t0, c1


def coarse_turning_points(
    decay: Any, time: ArrayLike, displacement: ArrayLike | None
) -> NDArray | None:
    """A decay's turning points from its displacement's staircase, where it is coarse.

    Parameters
    ----------
    decay : EnergyDecay
        The run's energy decay (:func:`bayestribo.signal.decay.energy_decay`): its
        turning points, noise levels and steps.
    time : array_like
        The recording's time stamps [s], as the decay was measured on.
    displacement : array_like or None
        The recorded displacement [length unit] (None: not recorded).

    Returns
    -------
    ndarray or None
        :func:`staircase_turning_points` of the decay's turning points, about its
        equilibrium (NaN where a swing crosses no boundary); None where the displacement
        is not recorded, or not coarse (its noise dithers the steps: the turning points'
        parabolas hold), or the staircase gives no answer.
    """
    noise = decay.noise
    if displacement is None or decay.derived_channel == "displacement":
        return None
    step = coarse_steps((noise.displacement_step, None), (noise.displacement, None))[0]
    peaks = decay.peaks
    if step is None or peaks.kind != "displacement" or len(peaks) < 2:
        return None
    rest = getattr(decay.rest_noise, "displacement", None)
    # the noise measured at rest (a rest on one level: none), not the floor of q/√12
    level = math.sqrt(rest.variance) if rest is not None else float(noise.displacement)
    found = staircase_turning_points(
        time,
        displacement,
        peaks.t,
        np.sign(peaks.value),
        step,
        math.pi / peaks.half_period,
        noise=level,
        fit_drift=peaks.drift != 0.0,
    )
    return None if found is None else found[0]
