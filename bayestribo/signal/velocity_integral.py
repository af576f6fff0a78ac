"""The integral of an acceleration as a velocity, in linear steps.

The steps of :func:`bayestribo.io.acceleration.integrate_acceleration` after the bias
is removed: the integral in the frequency domain, its drift measured at rest taken off
(:func:`rest_drift`), the zero-phase high-pass (:func:`highpass_gain`,
:func:`lowpass_part`) with the displacement's steps at the edges kept. All are linear
in the acceleration, so that the sensor's noise can be drawn through them
(:func:`velocity_noise`) for the noise model of the increments
(:mod:`bayestribo.signal.increments`); the module notes of
:mod:`bayestribo.io.acceleration` say why each step is as it is.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "ORDER",
    "REST_SAMPLES",
    "highpass_gain",
    "integrated_velocity",
    "lowpass_part",
    "rest_drift",
    "velocity_noise",
]

#: Order n of the Butterworth high-pass whose squared magnitude is applied (zero phase).
ORDER = 2
#: Samples of rest each side of the motion needs for its drift to be measured there.
REST_SAMPLES = 8
#: Terms of the low-frequency content of a free decay's edge (the release, the stop)
#: kept out of the high-pass: the displacement's step and its first four derivatives.
_MULTIPOLES = 3
#: Spectral width of the Gaussian that smooths the edge's terms, in cut-offs f_c.
_SMOOTHING = 16.0


def highpass_gain(f: ArrayLike, cutoff_Hz: float) -> NDArray:
    """Gain of the zero-phase high-pass at frequencies ``f`` [Hz]: r / (1 + r), r = (f/f_c)⁴.

    Parameters
    ----------
    f : array_like
        Frequencies [Hz].
    cutoff_Hz : float
        The cut-off f_c [Hz] (gain 1/2 there).

    Returns
    -------
    ndarray
        The gain, real and in [0, 1).
    """
    r = (np.abs(np.asarray(f, dtype=float)) / cutoff_Hz) ** (2 * ORDER)
    return r / (1.0 + r)


def rest_drift(t: NDArray, v: NDArray, before: NDArray, after: NDArray) -> NDArray:
    """The drift of an integrated velocity, measured at rest: a line through each rest,
    between them the straight line from the first's end to the second's start (the
    best estimate of a random walk known at both ends), and beyond a rest on one side
    only, the level at its end (a random walk's best estimate past its last value)."""
    lines = []
    for mask in (before, after):
        if int(mask.sum()) >= REST_SAMPLES:
            tm = t[mask]
            centre = float(tm.mean())
            offsets = tm - centre
            at_rest = v[..., mask]  # rows of draws too (velocity_noise)
            level = at_rest.mean(axis=-1, keepdims=True)
            slope = (at_rest - level) @ offsets / float(offsets @ offsets)
            lines.append((centre, level, slope[..., None], float(tm[0]), float(tm[-1])))
        else:
            lines.append(None)
    first, second = lines
    if first is None and second is None:
        return np.zeros_like(v)
    if second is None:
        c, level, slope, _, end = first
        return level + slope * (np.minimum(t, end) - c)
    if first is None:
        c, level, slope, start, _ = second
        return level + slope * (np.maximum(t, start) - c)
    cb, vb, sb, _, t0 = first
    ca, va, sa, t1, _ = second
    d0, d1 = vb + sb * (t0 - cb), va + sa * (t1 - ca)
    return np.where(
        t <= t0,
        vb + sb * (t - cb),
        np.where(t >= t1, va + sa * (t - ca), d0 + (d1 - d0) * (t - t0) / (t1 - t0)),
    )


def lowpass_part(x: NDArray, dt: float, cutoff: float) -> NDArray:
    """What the zero-phase high-pass removes from ``x``: x filtered by 1 − H(f), the
    record extended at each end by its odd reflection about its end value over eight
    time constants (as ``scipy.signal.filtfilt`` pads), so that a record that ends in
    motion, or on a drift, ends without a jump."""
    from scipy.fft import irfft, next_fast_len, rfft, rfftfreq

    n = x.shape[-1]
    pad = min(n - 1, math.ceil(8.0 / (2.0 * math.pi * cutoff * dt)))
    left = 2.0 * x[..., :1] - x[..., pad:0:-1]
    right = 2.0 * x[..., -1:] - x[..., -2 : -pad - 2 : -1]
    extended = np.concatenate([left, x, right], axis=-1)
    m = next_fast_len(extended.shape[-1] + pad, real=True)
    f = rfftfreq(m, dt)
    low = irfft(rfft(extended, m, axis=-1) / (1.0 + (f / cutoff) ** (2 * ORDER)), m, axis=-1)
    return low[..., pad : pad + n]


def _edge_smoothing(f: NDArray, cutoff: float, dt: float) -> NDArray:
    """The spectrum of the Gaussian that smooths the edge's terms: spectral width
    16 f_c, an eighth of the sampling rate at most.

    A delta between two samples, unsmoothed, rings over the whole record (its spectrum
    reaches the Nyquist frequency, and its derivatives' grow there), and the odd
    reflection at the record's ends (:func:`lowpass_part`) turns that ringing into a
    low-frequency part at the ends; below a few f_c, where the edge's content is, the
    Gaussian is 1."""
    width = min(_SMOOTHING * cutoff, 0.125 / dt)
    return np.exp(-0.5 * (f / width) ** 2)


def _kept_steps(
    t: NDArray, low: NDArray, cutoff: float, times: list[float]
) -> tuple[NDArray, list[float]]:
    """The displacement's steps at ``times`` that best explain the low-frequency part
    ``low`` of a velocity (least squares), as that part of them, and their sizes [m].

    A free decay's velocity holds almost nothing below f_c but these steps
    (the held position to the centre of the oscillation at the release, the centre to
    the stuck position at the stop; a decay starting at a turning point puts a share
    (f_c/f)² of its swing there): the rest of ``low`` is the drift of the integral.
    Each step is a delta of the velocity at its time, with its first four derivatives
    for the shape of the edge, band-limited to the samples."""
    from scipy.fft import irfft, next_fast_len, rfftfreq

    dt = float(t[1] - t[0])
    m = next_fast_len(2 * t.size, real=True)
    f = rfftfreq(m, dt)
    columns = []
    smooth = _edge_smoothing(f, cutoff, dt)
    for tj in times:
        shift = smooth * np.exp(-2j * math.pi * f * (tj - t[0])) / dt
        for k in range(_MULTIPOLES):  # the step, and its derivatives (the edge's shape)
            delta = irfft(shift * (2j * math.pi * f * dt) ** k, m)[: t.size]
            columns.append(lowpass_part(delta, dt, cutoff))
    basis = np.column_stack(columns)
    # several rows of ``low`` at once (the draws of :func:`velocity_noise`)
    sizes, *_ = np.linalg.lstsq(basis, low.T, rcond=None)
    return (basis @ sizes).T, [float(x) for x in np.atleast_2d(sizes.T)[-1, ::_MULTIPOLES]]


def integrated_velocity(
    t: NDArray,
    a: NDArray,
    before: NDArray,
    after: NDArray,
    cutoff: float,
    edges: list[float],
) -> tuple[NDArray, list[float]]:
    """Steps 2 and 3 of the module notes on an acceleration without its bias: the
    integral, its drift measured at rest taken off, and the high-pass with the
    displacement's steps at ``edges`` kept; linear in ``a`` (rows of samples for
    several). Returns the velocity and the steps' sizes (of the last row)."""
    from scipy.fft import irfft, next_fast_len, rfft, rfftfreq

    dt = float(t[1] - t[0])
    n = t.size
    m = next_fast_len(2 * n, real=True)
    f = rfftfreq(m, dt)
    response = np.zeros(f.size, dtype=np.complex128)
    response[1:] = 1.0 / (2j * math.pi * f[1:])
    if m % 2 == 0:
        response[-1] = 0.0  # Nyquist: the integral of a real signal there is not real
    rows = np.atleast_2d(a)
    velocity = irfft(rfft(rows, m, axis=-1) * response, m, axis=-1)[:, :n]
    velocity = velocity - rest_drift(t, velocity, before, after)
    low = lowpass_part(velocity, dt, cutoff)
    sizes: list[float] = []
    if edges:
        kept, sizes = _kept_steps(t, low, cutoff, edges)
        low = low - kept
    out = velocity - low
    return (out[0] if np.ndim(a) == 1 else out), sizes


def velocity_noise(noise: Mapping[str, Any], count: int, rng: np.random.Generator) -> NDArray:
    """Draws of the noise an integrated velocity holds: the sensor's white noise put
    through the integration (:func:`integrate_acceleration`'s linear steps, with the
    rests, edges and cut-off it found).

    The rest's spectrum of the velocity does not show this noise in the motion: the
    drift between the two rests is the straight line from one to the other, so the
    integrated noise is a random walk held at the rests and free between them, of
    which the high-pass leaves a part near its cut-off (measured on a dry-friction
    record with 3 s of motion: the velocity's noise in the motion 2.7 times the rest's).

    Parameters
    ----------
    noise : mapping
        The integration's ``noise`` record (:meth:`Integration.record`): the
        acceleration's noise ``sigma`` at rest [m/s² or rad/s²], the sampling, the
        rests as index runs, the edges' times [s], the cut-off [Hz] and the gain
        divided out.
    count : int
        Draws.
    rng : numpy.random.Generator
        Their source.

    Returns
    -------
    ndarray
        Shape (count, samples): velocity noise [m/s or rad/s] on the record's samples.
    """
    if noise.get("kind") == "high_pass":
        from bayestribo.signal.high_pass import high_pass_noise

        return high_pass_noise(noise, count, rng)
    n = int(noise["samples"])
    t = float(noise["start_s"]) + float(noise["step_s"]) * np.arange(n)
    masks = []
    for key in ("rest_before", "rest_after"):
        mask = np.zeros(n, dtype=bool)
        for first, stop in noise[key]:
            mask[first:stop] = True
        masks.append(mask)
    rest = masks[0] | masks[1]
    a = rng.normal(0.0, float(noise["sigma"]), (count, n))
    a -= a[:, rest].mean(axis=1, keepdims=True)  # the bias measured at rest
    edges = [float(e) for e in noise["edges_s"]]
    velocity, _ = integrated_velocity(t, a, masks[0], masks[1], float(noise["cutoff_Hz"]), edges)
    return velocity / float(noise["gain"])
