"""Where the motion is in a record: release, end of motion, and the rest around them.

A free-decay record holds rest (the pin held before the release, stuck after the
stop), the decaying oscillation between them, and noise everywhere. Whether a stretch
is rest cannot be judged from its level alone (a filtered, humming or 1/f noise can
wander far beyond a white-noise band, and the longer the rest the further), so
:func:`motion_span` judges it by the physics: **motion is a coherent oscillation at
the rig's frequency**.

* The velocity (recorded, or derived from the displacement) is cut into blocks of two
  periods, overlapping by half. In each block a constant, a line and a sinusoid at the
  oscillation frequency are fitted by least squares; the block is *moving* when the
  sinusoid explains more than half of what the line leaves (amplitude above about 1.4
  times the noise per sample), *quiet* otherwise. Noise of any colour puts only a
  fraction of its power at the oscillation frequency (1/f noise about 15 %, a 50 Hz
  line almost none over two periods of 32.6 Hz), so rest is quiet however long.
* The motion runs from the first to the last moving block. The rest noise σ is the
  median, over the quiet blocks, of the standard deviation about each block's line:
  a figure that does not grow with the length of the rest.
* The **end of motion** is refined in the last moving block and the block after it
  only (so the length of the rest cannot move it): the velocity's last excursion
  beyond ``threshold`` σ from its level at rest, then its next crossing of that
  level, linearly interpolated; with dry friction this is the last turning point,
  where the pin sticks (the velocity reaches zero with a slope Ω²|x - x_c| > 0, so
  the crossing is sharp). The **release** is found the same way from the front: the
  last crossing of the rest level before the first excursion beyond the threshold.
  This is a hysteresis: motion is entered only beyond ``threshold`` σ and left only at
  the rest level itself, reached by extrapolating a cubic through the samples of the
  last (first) eighth of a period on the moving side, a third of it away from the
  crossing (where an anti-alias filter rounds the corner), not by waiting for the
  noise to cross it.
* **A last half cycle under the threshold**: a displacement recorded beside the
  velocity (``beside``) that is not at its rest where the threshold ended the motion
  shows the motion going on (a last swing of ten displacement σ peaks at five velocity
  σ). The end of motion is then the end of the last lobe of the velocity, averaged over
  an eighth of a period, that stands out of that mean's noise: half a period after the
  crossing that starts it, from the crossings' spacing before it
  (:func:`_missed_half_cycle`). Before, the oscillator seemed stuck a half cycle early,
  and μ_s/μ_k came out 3.0 [2.0, 4.0] where it was 1, exit 0. A velocity recorded alone
  (``velocity_alone``) whose oscillation stops (no fade) ends at one more half cycle
  where that lobe itself stands out of the noise of the velocity's mean, measured on
  the rest a block later, not taken as white (:func:`_missed_alone`; was μ_s/μ_k 2.9
  [2.0, 3.9] where it was 1, exit 0).
* A **quantised displacement** (given as ``periodic``) is judged the same way, on its
  own blocks, with the sinusoid's first three harmonics: a swing of a few steps, or
  below one, toggles the displacement between levels at the oscillation frequency
  (motion, not rest) long after the velocity derived from it is buried in rounding
  noise; a rest on one level or toggling at random has no such periodicity. The
  motion runs on as long as either channel's blocks are coherent, and then ends at
  the displacement's last change of level (its rest level is the tail's median) where
  the rest stays on its level (at most :data:`STEADY_REST` of its samples off it: steps
  coarse beside the noise). Where the noise toggles the rest between levels (steps of
  the order of the noise, a vibrometer's), a last change of level is the noise's, and
  the end of motion is the last excursion beyond the threshold, as without steps. The
  analysis gives no such displacement where its noise spans four steps or more
  (:func:`bayestribo.signal.quantisation.finely_dithered`: a file written with five
  decimals of metres under 0.2 mm of noise): its levels are a continuous signal's, and
  judged as levels the block holding its last swing and a rest shorter than a block
  was coherent, so that the stop was not found.
* **A velocity recorded alone** (``velocity_alone``: a seismometer's coil, its
  displacement to be integrated) may hold a **viscous decay that fades into the noise**
  instead of stopping: its last excursion beyond the threshold is then followed by a
  coherent oscillation at the rig's frequency (the two periods after it are a moving
  block, which after a dry-friction stop are the rest's noise). That crossing is not an
  end of motion (:attr:`MotionSpan.fade_time`): the rest starts after the last moving
  block, and the analysis ends before the crossing, as for a record that ends in motion.
  Taken for a stop, it set the model's energy after it to zero and counted the
  oscillation under the threshold as rest noise (ζ 2.5 to 5 sd low on a seismometer's
  record, ``tests/test_signal_seismometer.py``). Its **rest before the release** may be
  shorter than a block, the first block then moving: a first quarter period within the
  threshold of its median is rest, and the release is its first excursion beyond it
  (else the integral's wander at rest gave a turning point).
* **A slow rig's rests**, shorter than a block (a 1 Hz spring held a second before its
  release): with a velocity recorded beside the displacement, a quiet block next to the
  motion whose quarters spread unevenly (one of them beyond :data:`QUARTER_SPREAD`
  times their median: the release's first instants) is not rest; where no block is
  left wholly in a rest, the noise is read off the velocity's second differences
  (:func:`bayestribo.signal.difference_noise.difference_noise`: white noise, many
  samples a period), not the median of the blocks left out of the motion, which hold
  its first and last swings; and where the first (last) block moves, the release
  (stop) is the first (last) excursion beyond the threshold when the first (last)
  eighth of a period lies within it and the rest beside it spreads by at most
  :data:`REST_SPREAD` σ. Before, such records were refused ("found 0 usable extrema")
  or taken to start or end in motion (a mass stuck off centre counted as moving).
* The blocks' sinusoid is at the frequency measured from the record's own spectrum
  (a peak of the spectrum of its first difference: the one whose oscillation is the
  strongest in the signal itself, so that a line of the noise that the difference
  gains is not taken for it; :func:`bayestribo.signal.period.dominant_period`).

:func:`check_turning_points` applies the other piece of physics: consecutive turning
points of the motion are half a damped period apart. :func:`regular_turning_points`
applies it to a record whose start is not yet the free decay (large swings of a
pendulum, whose period grows with the amplitude; an oscillator still driven, by a
hand or a blow, for its first cycles): the analysis starts where the spacing becomes
regular, and an irregular interval after two regular oscillations is refused as a
wiggle of the noise or a missed turning point.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.errors import RecordingError
from bayestribo.signal.difference_noise import difference_noise
from bayestribo.signal.period import sample_step

__all__ = [
    "IrregularStartWarning",
    "MotionSpan",
    "RegularTurningPoints",
    "block_noise",
    "check_turning_points",
    "lobes_after_stop",
    "motion_span",
    "regular_turning_points",
]

#: Fraction of a block's variance the oscillation must explain for it to be moving.
COHERENCE = 0.5
#: Excursion of a displacement from its rest level, in rest noise standard deviations,
#: that ends the motion when the velocity was derived (Gaussian tail 6e-7 per sample).
DISPLACEMENT_THRESHOLD = 5.0
#: Largest fraction of a quantised displacement's samples at rest off its rest level for
#: the end of motion to be its last change of level: above it the noise toggles the
#: rest between levels, and a change of level marks nothing.
STEADY_REST = 0.2
#: Most levels of a quantised displacement whose levels place the release when the
#: velocity's threshold does not (a coarse digitiser's: 3 to 10 steps across the swing
#: and its noise's toggling take 4 to 14; a fine one's thousands).
FEW_LEVELS = 32
#: Most levels of a displacement whose release the levels place even where the
#: velocity crosses its threshold, when that threshold is beyond half the first swings
#: (3 to 5 steps across the swing and the noise's toggling: 4 to 7 levels). At 10 steps
#: (11 to 13 levels) the velocity's crossing is kept: the levels moved the release by
#: a millisecond there and a turning point was then missed (measured on
#: ``benchmarks/coarse_dissipation.py``'s records).
COARSE_LEVELS = 8
#: Another run of moving blocks is a separate motion (another release, a knock) when it
#: spans at least two blocks (three periods) and its oscillation reaches this fraction
#: of the largest motion's (its blocks' coherent part, rms): a decay's fading tail that
#: a block of noise cuts off from it is a few hundredths of its release at most.
SEPARATE_MOTION = 0.1
#: Blocks (two periods each) of rest kept beside a motion on a side where the record
#: holds another: the rest's noise is measured on them, and what lies beyond (a mass
#: pulled back to its hold for the next release) is not rest.
REST_BESIDE = 4
#: Excursion of the velocity's mean over an eighth of a period, in that mean's white
#: noise σ/√samples, that marks a last half cycle once the displacement recorded beside
#: the velocity shows the oscillator moved after the stop :data:`THRESHOLD` found
#: (:func:`_missed_half_cycle`; at 3, noise at rest reached it within a period).
MISSED_THRESHOLD = 5.0
#: Periods after the end its threshold found within which :func:`lobes_after_stop`
#: looks for last swings under it (a slow rig's last four half cycles of a few σ).
LOBES_REACH = 3.0
#: Default excursion threshold, in rest noise standard deviations, that marks motion
#: when the release and the end of motion are refined (a Gaussian sample exceeds 8σ
#: with probability 1e-15).
THRESHOLD = 8.0
#: Largest accepted relative deviation of a turning-point interval from the half period.
SPACING_TOLERANCE = 0.3
#: Regular intervals in a row (two oscillations) after which an irregular interval is
#: inside the decay (a wiggle of the noise, a missed turning point), not its start.
REGULAR_RUN = 4
#: Largest departure, in half periods, of the first turning point of a regular run
#: after an irregular start from the cubic through the next :data:`SETTLE_POINTS`.
SETTLE = 0.02
#: Turning points whose cubic in their index continues the run to its first one.
SETTLE_POINTS = 8


class IrregularStartWarning(UserWarning):
    """The first turning points of a record are not half a period apart (large swings
    whose period depends on the amplitude, a start still driven): they were left out of
    the analysis, which starts where the spacing becomes regular (the message names the
    turning points left out, their times and their spacing)."""


@dataclass(frozen=True)
class MotionSpan:
    """The motion inside a record and the rest around it.

    Attributes
    ----------
    release_index : int or None
        Last sample of the rest the record starts in, ``None`` for a record that
        starts in motion.
    release_time : float or None
        Time of the release [s] (linearly interpolated crossing), or ``None``.
    stop_index : int or None
        Last sample at or before the end of motion, ``None`` when the motion lasts to
        the end of the record.
    stop_time : float or None
        End of motion [s] (interpolated crossing of the rest level), or ``None``.
    quiet : ndarray of bool
        Samples of the quiet head (before the release) and tail (after the stop).
    noise : float
        Rest noise standard deviation of the velocity channel used [unit/s].
    threshold : float
        Excursion threshold used [unit/s] (``THRESHOLD`` times ``noise``).
    block : int
        Samples per block (two periods).
    fade_time : float or None
        When the oscillation fades into the noise instead of stopping (asked for with
        ``velocity_alone``): the end of the last block holding it [s], where ``quiet`` starts;
        ``stop_time`` is then where its swings sink below ``threshold``, not an end of
        motion. ``None`` otherwise.
    bounds : (int, int) or None
        Where the record holds other motions than this one, separated from it by rest
        (:data:`SEPARATE_MOTION`): the samples ``[lo, hi)`` from the end of the one
        before to the start of the one after, which hold this motion and its rests;
        ``None`` when it is the record's only motion. The span's other fields are then
        not to be used: the record is analysed again within the bounds.
    others : tuple of (float, float)
        The other motions' spans [s] (their first and last moving blocks).
    """

    release_index: int | None
    release_time: float | None
    stop_index: int | None
    stop_time: float | None
    quiet: NDArray
    noise: float
    threshold: float
    block: int
    fade_time: float | None = None
    bounds: tuple[int, int] | None = None
    others: tuple[tuple[float, float], ...] = ()

    @property
    def motion_ended(self) -> bool:
        """True when the record holds the end of motion (not a fade into the noise)."""
        return self.stop_time is not None and self.fade_time is None


#: Samples of blocks taken together by :func:`_block_fits` (4 MB of float64 at most).
_CHUNK = 1 << 19


def _block_fits(
    t: NDArray, s: NDArray, starts: NDArray, size: int, omega: float
) -> tuple[NDArray, NDArray]:
    """Per block of ``size`` samples from each of ``starts``: the mean square left by a
    line, and by a line and a sinusoid at ``omega`` [rad/s] (the sinusoid only when
    ``omega`` is not 0; else the second array repeats the first).

    The blocks are views of ``s`` (no copy of the overlapping blocks), taken a few at a
    time; each is detrended by its line (the constant and the centred time are
    orthogonal), and the sinusoid's share is the squared projection of what the line
    leaves on an orthonormal basis of the sinusoid's part outside the line (the
    variance it explains). At 1,000,001 samples in 32 blocks of 61,000 (half
    overlapping): 25 ms instead of 130 ms for a copy of the blocks and two
    pseudo-inverse projections, with the same mean squares to 1e-12.
    """
    starts = np.asarray(starts, dtype=np.int64)
    tt = t[:size] - t[0]
    tt = tt - tt.mean()
    line = tt / math.sqrt(float(tt @ tt)) if np.any(tt) else np.zeros(size)
    wave = None
    if omega != 0.0:
        basis = np.stack([np.cos(omega * tt), np.sin(omega * tt)])
        basis -= basis.mean(axis=1, keepdims=True)
        basis -= np.outer(basis @ line, line)
        u, sv, _ = np.linalg.svd(basis.T, full_matrices=False)
        # the rank numpy.linalg.pinv gives the line and the sinusoid together
        wave = u[:, sv > size * np.finfo(float).eps * max(float(sv.max()), math.sqrt(size))]
    windows = np.lib.stride_tricks.sliding_window_view(s, size)
    var1 = np.empty(starts.size)
    var2 = np.empty(starts.size)
    step = max(1, _CHUNK // size)
    for first in range(0, starts.size, step):
        rows = windows[starts[first : first + step]]
        rows -= rows.mean(axis=1, keepdims=True)
        # products by einsum, not a threaded BLAS: these are bound by memory, and a
        # BLAS thread waiting for a busy second core took 4 times as long
        rows -= np.einsum("ij,j->i", rows, line)[:, None] * line
        part = slice(first, first + rows.shape[0])
        var1[part] = np.einsum("ij,ij->i", rows, rows) / size
        if wave is not None and wave.shape[1]:
            projected = np.einsum("ij,jk->ik", rows, wave)
            explained = np.einsum("ij,ij->i", projected, projected) / size
            var2[part] = np.maximum(var1[part] - explained, 0.0)
        else:
            var2[part] = var1[part]
    return var1, var2


def _harmonic_coherence(
    t: NDArray, s: NDArray, starts: NDArray, size: int, omega: float
) -> NDArray:
    """Fraction of each block's variance about its line that sinusoids at ``omega`` and
    its second and third harmonics [rad/s] explain (0 for a block on one level)."""
    var1, _ = _block_fits(t, s, starts, size, 0.0)
    tt = t[:size] - t[0]
    tt = tt - tt.mean()
    columns = [np.ones(size), tt]
    for k in (1, 2, 3):
        columns += [np.cos(k * omega * tt), np.sin(k * omega * tt)]
    basis, _ = np.linalg.qr(np.column_stack(columns))
    wave = basis[:, 2:]
    windows = np.lib.stride_tricks.sliding_window_view(s, size)[starts]
    centred = windows - windows.mean(axis=1, keepdims=True)
    projected = centred @ wave
    explained = np.einsum("ij,ij->i", projected, projected) / size
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(var1 > 0, np.minimum(explained / var1, 1.0), 0.0)


def block_noise(t: NDArray, s: NDArray, mask: NDArray, size: int) -> float | None:
    """Median standard deviation of ``s`` about a line over blocks inside ``mask``.

    The noise of a channel at rest on the scale of ``size`` samples (two periods),
    insensitive to a slow wander of the rest level and to the length of the rest.
    Returns ``None`` when ``mask`` holds no whole block.
    """
    values: list[float] = []
    m = np.asarray(mask, bool)
    edges = np.flatnonzero(np.diff(np.r_[0, m.astype(np.int8), 0]))
    size = max(8, int(size))
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        if b - a < size:
            continue
        starts = np.arange(a, b - size + 1, size)
        var1, _ = _block_fits(t, s, starts, size, 0.0)
        values.extend(var1.tolist())
    if not values:
        return None
    return float(math.sqrt(np.median(values)))


def _root(t: NDArray, s: NDArray, level: float, lo: int, hi: int, near: int) -> float | None:
    """Where a cubic fitted to s[lo:hi] reaches ``level``: the real root nearest t[near].

    The velocity reaches its rest level at a turning point with a non-zero slope
    (Ω²|x - x_c|), and stays there once stuck; the crossing is extrapolated from the
    moving side, where the signal stands out of the noise, not looked for among the
    noise at rest.
    """
    if hi - lo < 6:
        return None
    origin = float(t[near])
    scale = float(t[hi - 1] - t[lo]) or 1.0
    u = (t[lo:hi] - origin) / scale
    coef = np.polyfit(u, s[lo:hi] - level, 3)
    roots = np.roots(coef)
    real = roots[np.abs(roots.imag) < 1e-9].real
    if real.size == 0:
        return None
    r = float(real[np.argmin(np.abs(real))])
    return origin + r * scale


def _missed_half_cycle(
    t: NDArray,
    v: NDArray,
    x: NDArray,
    stop: int,
    stop_time: float,
    level: float,
    sigma: float,
    size: int,
) -> tuple[int, float] | None:
    """The end of a last half cycle the velocity's threshold missed, or None.

    A stuck oscillator rests where it stopped: the displacement recorded beside the
    velocity stays at its level from the stop on. Where one of its medians over eighths
    of a period, from the stop found to three quarters of a period after it, is farther
    than :data:`DISPLACEMENT_THRESHOLD` times its rest noise from the rest level after
    it (both measured on the rest a block after the stop, past any half cycle missed;
    the noise of a sample, not the level's standard error, which a noise that wanders —
    1/f, a filter's — exceeds), the motion went on: a last half cycle whose velocity
    peaked below the threshold (a swing of ten displacement σ peaks at five velocity σ
    at 5 kHz and 20 Hz), which the threshold put into the rest, so that the oscillator
    seemed stuck at the turning point before it (μ_s/μ_k 3.0 [2.0, 4.0] where it was 1,
    exit 0); or a last half cycle whose excursion the threshold caught but whose end it
    could not place.

    The velocity averaged over an eighth of a period (a centred mean: it keeps the
    crossing of a line where it is) is cut at its crossings of the rest level into
    lobes, from two periods before the stop found to three quarters of one after it; a
    lobe whose mean exceeds :data:`MISSED_THRESHOLD` times that mean's white noise is
    motion (a lobe of one sign stands out of noise averaged down by √samples, a sample
    of noise does not). The last such lobe ends where the oscillator sticks: half a
    period after the crossing that starts it (turning points are half a damped period
    apart whatever the friction, Eq. 13; the half period is the slope of the crossings
    between lobes before it against their count), not at the velocity's own return to its level,
    which is in its noise.
    """
    n = t.size
    if n - stop - 1 < max(8, size // 4):
        return None
    eighth = max(3, round(size / 16.0))  # an eighth of a period
    # the displacement from the stop found on, to the end of the half cycle after it:
    # its medians over eighths of a period (where the threshold's stop lies inside a
    # half cycle, the displacement there is near the swing's centre, and the turning
    # point after it is off the rest)
    ahead = x[max(0, stop - eighth // 2) : min(n, stop + 1 + size // 4 + size // 8)]
    chunks = ahead[: ahead.size // eighth * eighth].reshape(-1, eighth)
    # the rest a block after the stop (the block right after holds the half cycle, if
    # one was missed); the block after the stop where the record ends sooner
    start = stop + 1 + size
    if n - start >= size:
        later = np.r_[np.zeros(start, bool), np.ones(n - start, bool)]
        sigma_x = block_noise(t, x, later, size)
        level_x = float(np.median(x[start : start + size]))
    else:
        after = np.r_[np.zeros(stop + 1, bool), np.ones(n - stop - 1, bool)]
        sigma_x = block_noise(t, x, after, min(size, n - stop - 1))
        level_x = float(np.median(x[stop + 1 : stop + 1 + size]))
    if not sigma_x or not chunks.size:
        return None
    off = float(np.max(np.abs(np.median(chunks, axis=1) - level_x)))
    if off <= DISPLACEMENT_THRESHOLD * sigma_x:
        return None
    end_time = _last_lobe_end(t, v - level, stop, size, eighth, sigma / math.sqrt(eighth))
    if end_time is None or not end_time > stop_time:
        return None
    index = int(np.searchsorted(t, end_time, side="right")) - 1
    if index >= n - 1:
        return None
    # the displacement rests at its level from there on (else not a stop either)
    settled = x[min(n - 1, index + eighth) : min(n, index + eighth + size // 4)]
    if settled.size and abs(float(np.median(settled)) - level_x) > DISPLACEMENT_THRESHOLD * sigma_x:
        return None
    return index, end_time


def _mean_noise(rest: NDArray, eighth: int, sigma: float) -> float:
    """The noise of a channel's mean over ``eighth`` samples: its white noise's,
    ``sigma``/√``eighth``, or the standard deviation of that mean over ``rest`` (samples
    at rest, about their level; none: white) where that is larger, a noise that is not
    white (mains hum, 1/f, an integral's) not being √samples smaller in the mean."""
    white = sigma / math.sqrt(eighth)
    if rest.size < 2 * eighth:
        return white
    means = np.convolve(rest, np.full(eighth, 1.0 / eighth), mode="valid")
    return max(white, float(np.std(means)))


def _last_lobe_end(
    t: NDArray, u: NDArray, stop: int, size: int, eighth: int, mean_noise: float
) -> float | None:
    """Where the last lobe of ``u`` (the velocity about its rest level) standing out
    of its mean's noise ``mean_noise`` ends [s] (:func:`_lobes`): half a period after
    the crossing that starts it, the half period the slope of the crossings between
    lobes before it against their count (half a block where fewer than two); None
    where no lobe but the first stands out."""
    crossings, lobes = _lobes(t, u, stop, size, eighth, mean_noise)
    found = np.flatnonzero(lobes)
    if not found.size or found[-1] == 0:
        return None
    last = int(found[-1])
    run = [last - 1]
    while run[-1] > 0 and lobes[run[-1] - 1]:
        run.append(run[-1] - 1)
    between = np.array([crossings[k] for k in reversed(run)])
    half = 0.25 * size * float(t[-1] - t[0]) / (t.size - 1)
    if between.size >= 2:
        half = float(np.polyfit(np.arange(between.size), between, 1)[0])
    return crossings[last - 1] + half


def _missed_alone(
    t: NDArray, v: NDArray, stop: int, stop_time: float, level: float, sigma: float, size: int
) -> tuple[int, float] | None:
    """The end of a last half cycle the threshold missed in a velocity recorded alone,
    or None (:func:`_missed_half_cycle` without a displacement to show the motion went
    on: the lobe itself must stand out of the noise of the velocity's mean over an
    eighth of a period, measured on the rest a block after the stop where the record
    holds two blocks of it, not taken as white: a coloured noise's mean over many
    samples is not √samples smaller). Only a lobe starting at the stop (within a
    quarter period) counts: one more half cycle, the oscillator sticking at its end,
    which must be followed by rest (no further lobe)."""
    n = t.size
    eighth = max(3, round(size / 16.0))
    start = stop + 1 + size
    if n - start < 2 * size:
        return None
    mean_noise = _mean_noise(v[start:] - level, eighth, sigma)
    end_time = _last_lobe_end(t, v - level, stop, size, eighth, mean_noise)
    dt = float(t[-1] - t[0]) / (n - 1)
    if end_time is None or not end_time > stop_time + 0.125 * size * dt:
        return None
    if end_time > stop_time + 0.375 * size * dt:  # more than one half cycle on
        return None
    index = int(np.searchsorted(t, end_time, side="right")) - 1
    return (index, end_time) if index < n - 1 else None


def _lobes(
    t: NDArray, u: NDArray, stop: int, size: int, eighth: int, mean_noise: float
) -> tuple[list[float], NDArray]:
    """The crossings of zero [s] by ``u`` averaged over ``eighth`` samples (centred),
    from a block before sample ``stop`` to three eighths of one after it, a
    crossing within a quarter period of the one before left out (the noise's, near a
    turning point); and per lobe between them (one more than the crossings, the first
    and last open), whether its mean exceeds :data:`MISSED_THRESHOLD` times the
    mean's noise ``mean_noise`` (white: σ/√``eighth``)."""
    lo = max(0, stop + 1 - size - eighth)
    hi = min(t.size, stop + 1 + size // 4 + size // 8)
    kernel = np.full(eighth, 1.0 / eighth)
    s = np.convolve(u[lo:hi], kernel, mode="valid")
    tt = np.convolve(t[lo:hi], kernel, mode="valid")
    dt = float(t[-1] - t[0]) / (t.size - 1)
    quarter = 0.125 * size * dt
    crossings: list[float] = []
    cut: list[int] = []
    for k in np.flatnonzero(np.signbit(s[:-1]) != np.signbit(s[1:])).tolist():
        a, b = float(s[k]), float(s[k + 1])
        tc = float(tt[k] + (tt[k + 1] - tt[k]) * a / (a - b)) if a != b else float(tt[k])
        if not crossings or tc - crossings[-1] > quarter:
            crossings.append(tc)
            cut.append(k + 1)
    edges = [0, *cut, s.size]
    limit = MISSED_THRESHOLD * mean_noise
    lobes = np.array([bool(np.any(np.abs(s[a:b]) > limit)) for a, b in itertools.pairwise(edges)])
    # the frequency of the lobes' arcs: their crossings' spacing (the mean's bias is
    # about the same at each), else the block's two periods
    inner = [c for k, c in enumerate(crossings) if lobes[k] and lobes[k + 1]]
    omega = 4.0 * math.pi / (size * dt)
    if len(inner) >= 2:
        omega = math.pi / float(np.polyfit(np.arange(len(inner)), inner, 1)[0])
    return [_crossing(t, u, c, eighth, omega) for c in crossings], lobes


def _crossing(t: NDArray, u: NDArray, near: float, eighth: int, omega: float) -> float:
    """The crossing of zero by ``u`` whose centred mean over ``eighth`` samples crosses
    at ``near`` [s], from the samples before it. A turning point's velocity is not odd
    about it (friction adds to the spring's force before it and takes from it after,
    Ω²(|x| ± x_c)): the mean crosses up to half its window late, half a window where the
    oscillator sticks. The quarter period of samples before that reach is an arc of a
    sinusoid at ``omega`` [rad/s] (the half cycle's motion about its centre): the zero
    of the sinusoid fitted to it by least squares is the crossing, kept where it lands
    within the reach and a sample of ``near``."""
    dt = float(t[-1] - t[0]) / (t.size - 1)
    half = 0.5 * eighth * dt
    hi = int(np.searchsorted(t, near - half, side="right"))
    lo = max(0, hi - 2 * eighth)
    if hi - lo < 4 or not omega > 0.0:
        return near
    s = t[lo:hi] - t[hi - 1]
    basis = np.column_stack([np.sin(omega * s), np.cos(omega * s)])
    (a, b), *_ = np.linalg.lstsq(basis, u[lo:hi], rcond=None)
    # a sin ωs + b cos ωs = 0: s = atan2(-b, a)/ω modulo π/ω, the one nearest ``near``
    first = math.atan2(-b, a) / omega
    step = math.pi / omega
    target = near - float(t[hi - 1])
    root = float(t[hi - 1]) + first + step * round((target - first) / step)
    if not near - half - dt <= root <= near + dt:
        return near
    return root


def lobes_after_stop(
    t: NDArray, s: NDArray, stop_time: float, noise: float, period: float
) -> float:
    """The end of motion moved past the lobes of a white-noise channel that follow the
    end its threshold found [s] (``stop_time`` when none does).

    A last half cycle whose peak stays below the threshold (:data:`THRESHOLD` σ) is
    taken for rest by it: an accelerometer's last swings of a few friction
    displacements peak at a few σ (a 20 Hz rig, 2-10 µm swings: 0.06-0.16 m/s² under
    0.02 m/s² of noise), and the oscillator seemed to stick at the turning point where
    the threshold was last crossed, several friction displacements out (μ_s/μ_k 9.0
    [6.7, 9.9] where it was 1, exit 0). Such a lobe stands out of the noise averaged
    over an eighth of a period (its mean beyond :data:`MISSED_THRESHOLD` times the
    mean's noise: ``noise``/√samples for white noise, a chance of 6e-7 per window for
    noise alone; the standard deviation of the mean over the rest beyond
    :data:`LOBES_REACH` periods where that is larger, a noise that is not white): while
    one does within three quarters of a period after the end, up to
    :data:`LOBES_REACH` periods after the threshold's, the end moves to the last sample
    of the last such window (late by an eighth of a period at most, never early: the
    sticking turning point stays inside the motion).

    Parameters
    ----------
    t : ndarray
        Time stamps [s], regular.
    s : ndarray
        The channel (its white noise ``noise`` at rest), rest level its median after
        the end.
    stop_time : float
        The end of motion found by the threshold [s].
    noise : float
        The channel's white noise standard deviation at rest.
    period : float
        The oscillation's period [s].

    Returns
    -------
    float
        The end of motion [s].
    """
    n = t.size
    dt = float(t[-1] - t[0]) / (n - 1)
    eighth = max(3, round(period / dt / 8.0))
    reach = max(2 * eighth, round(0.75 * period / dt))
    stop = int(np.searchsorted(t, stop_time, side="right")) - 1
    if not noise > 0.0 or stop < 0 or n - stop - 1 < reach + eighth:
        return stop_time
    level = float(np.median(s[stop + 1 :]))
    kernel = np.full(eighth, 1.0 / eighth)
    # the mean's noise measured on the rest beyond the reach of the lobes looked for
    # (LOBES_REACH periods after the end), where it holds two periods: a noise that is
    # not white (mains hum, 1/f) is not √samples smaller in the mean, and its lobes would
    # carry the end through the rest
    far = stop + 1 + round((LOBES_REACH + 1.0) * period / dt)
    rest = s[far:] - level if n - far >= round(2.0 * period / dt) else s[:0]
    mean_noise = _mean_noise(rest, eighth, noise)
    limit = MISSED_THRESHOLD * mean_noise
    last = stop + round(LOBES_REACH * period / dt)
    end = stop_time
    while stop < last:
        window = s[stop + 1 : min(n, stop + 1 + reach)] - level
        if window.size < eighth:
            return end
        mean = np.convolve(window, kernel, mode="valid")
        out = np.flatnonzero(np.abs(mean) > limit)
        if not out.size:
            return end
        stop = stop + int(out[-1]) + eighth  # the window's last sample
        if stop >= n - 1:
            return end
        end = float(t[stop])
    return end


def motion_span(
    t: ArrayLike,
    velocity: ArrayLike,
    period: float,
    *,
    threshold: float = THRESHOLD,
    displacement: ArrayLike | None = None,
    periodic: ArrayLike | None = None,
    velocity_alone: bool = False,
    beside: ArrayLike | None = None,
) -> MotionSpan:
    """Release, end of motion and rest of a free-decay record (see the module notes).

    Parameters
    ----------
    t : array_like
        Time stamps [s], regular.
    velocity : array_like
        Velocity [unit/s], recorded or derived from the displacement.
    period : float
        Period of the oscillation [s] (about; it sets the blocks and the fitted
        sinusoid's frequency).
    threshold : float
        Excursion from the rest level, in rest noise standard deviations, that marks
        motion when the release and the end are refined.
    displacement : array_like, optional
        The recorded displacement [unit], when ``velocity`` was derived from it: a
        derivative's noise buries the last small swings, so the end of motion is then
        the last excursion of the displacement beyond :data:`DISPLACEMENT_THRESHOLD`
        of its rest noise from its rest level (within the same local window; the
        sticking turning point itself, approached quadratically, is not resolved).
    periodic : array_like, optional
        A recorded displacement quantised in steps [unit]: blocks where it toggles
        periodically at the oscillation frequency are moving too (see the module notes).
    velocity_alone : bool
        The velocity is the record's only channel (its displacement is its integral):
        judge whether its oscillation stops where its swings sink below ``threshold``
        or fades into the noise (a viscous decay never stops), and find a rest before
        the release that is shorter than a period (the integral's wander there would
        give turning points); see the module notes. Default False.
    beside : array_like, optional
        The displacement [unit] recorded beside a recorded ``velocity``: where it does
        not rest at its level at the stop the velocity's threshold found (a last half
        cycle whose velocity stayed below ``threshold`` σ), the end of motion is that
        half cycle's (see the module notes).

    Returns
    -------
    MotionSpan

    Raises
    ------
    RecordingError
        "release: no motion found" when no block holds an oscillation at the given
        period standing out of the noise; a bad ``period`` or ``threshold``.
    """
    t = np.asarray(t, dtype=float)
    v = np.asarray(velocity, dtype=float)
    if not (math.isfinite(period) and period > 0):
        raise RecordingError(f"period must be a positive number of seconds, got {period!r}")
    if not (math.isfinite(threshold) and threshold > 0):
        raise RecordingError(f"threshold must be a positive number, got {threshold!r}")
    n = v.size
    dt = sample_step(t)
    size = max(8, round(2.0 * period / dt))
    if n < size:
        raise RecordingError(
            f"release: the record holds {n} samples, fewer than two periods ({size}); "
            "no free decay can be found in it"
        )
    hop = max(1, size // 2)
    starts = np.arange(0, n - size + 1, hop)
    if starts[-1] != n - size:
        starts = np.r_[starts, n - size]
    var1, var2 = _block_fits(t, v, starts, size, 2.0 * math.pi / period)
    explained = np.where(var1 > 0, 1.0 - var2 / np.where(var1 > 0, var1, 1.0), 0.0)
    moving = explained > COHERENCE
    x_moving = None
    if periodic is not None:
        xp = np.asarray(periodic, dtype=float)
        x_moving = _harmonic_coherence(t, xp, starts, size, 2.0 * math.pi / period) > COHERENCE
    # a velocity derived from coarse steps may hold no coherent block: the steps do
    from_steps = x_moving is not None and not moving.any() and bool(x_moving.any())
    if from_steps:
        moving = x_moving.copy()
    if not moving.any():
        raise RecordingError(
            f"release: no motion found: no stretch of two periods ({2 * period:.4g} s) "
            "holds an oscillation at the record's dominant frequency above its noise"
        )
    # The motion is one run of moving blocks: the one holding the largest oscillation
    # (the release); a block of rest that happens to look coherent is not part of it.
    peak = int(np.argmax(moving if from_steps else np.where(moving, var1 - var2, -np.inf)))
    first = peak
    while first > 0 and moving[first - 1]:
        first -= 1
    last = peak
    while last < moving.size - 1 and moving[last + 1]:
        last += 1
    by_steps = from_steps
    if x_moving is not None:
        while last < moving.size - 1 and (moving[last + 1] or x_moving[last + 1]):
            by_steps = by_steps or not moving[last + 1]
            last += 1
    bounds, others = _separate_motions(t, moving, var1, var2, starts, size, first, last)
    moving = np.zeros_like(moving)
    moving[first : last + 1] = True
    quiet = np.zeros(n, bool)
    head_end = int(starts[first])  # samples before the first moving block
    tail_start = int(starts[last]) + size  # samples after the last moving block
    # A velocity recorded beside the displacement (neither derived from it, whose noise
    # is smoothed, nor alone, whose decay may fade instead of stopping): its rests may
    # be shorter than a block (a slow rig's), and are found so.
    recorded = displacement is None and not velocity_alone
    head_quiet = np.flatnonzero(starts[:first] + size <= head_end)
    tail_quiet = last + 1 + np.flatnonzero(starts[last + 1 :] >= tail_start)
    # the quiet block next to the motion holds the release's first (the stop's last)
    # instants where the block beside it, half of it motion, fell short of the
    # coherence (a rest of about two periods): no rest then
    if recorded and head_quiet.size and _holds_motion(t, v, int(starts[head_quiet[-1]]), size):
        head_quiet = head_quiet[:-1]
    if recorded and tail_quiet.size and _holds_motion(t, v, int(starts[tail_quiet[0]]), size):
        tail_quiet = tail_quiet[1:]
    quiet_blocks = var1[np.r_[head_quiet, tail_quiet]]
    sigma = float(math.sqrt(np.median(quiet_blocks))) if quiet_blocks.size else 0.0
    if quiet_blocks.size == 0 and not recorded:
        sigma = float(math.sqrt(np.median(var1[~moving]))) if (~moving).any() else 0.0
    elif quiet_blocks.size == 0:
        # no block lies wholly in a rest (rests shorter than two periods): the blocks
        # left out of the motion hold its first and last swings, and their median is
        # the motion's size, not the noise's; a white noise is read off the second
        # differences where the record holds many samples a period
        left_out = var1[~moving]
        sigma = float(math.sqrt(np.median(left_out))) if left_out.size else 0.0
        white = difference_noise(v, period / dt)
        if white is not None:
            sigma = min(sigma, white) if sigma > 0.0 else white
    # a noise-free record: excursions are measured against rounding
    sigma = max(sigma, 1e-8 * float(np.max(np.abs(v - np.median(v)))))
    level_cut = threshold * sigma

    # End of motion: refined near the last moving block only, so that the length of
    # the rest after it cannot move it.
    fit_len = max(9, round(period / dt / 8.0))
    skip = fit_len // 3  # samples next to the crossing, where a filter rounds the corner
    stop_index = stop_time = fade_time = None
    if tail_start + size // 2 <= n and not moving[-1]:
        lo = max(0, int(starts[last]) - size)
        hi = min(n, tail_start + size)
        rest = v[tail_start : min(n, tail_start + size)]
        level = float(np.median(rest))
        out = np.flatnonzero(np.abs(v[lo:hi] - level) > level_cut)
        if displacement is not None:
            x = np.asarray(displacement, dtype=float)
            rest_x = x[tail_start : min(n, tail_start + size)]
            after = np.r_[np.zeros(tail_start, bool), np.ones(n - tail_start, bool)]
            # a rest shorter than a block (the record ends a period or so after the
            # last moving block): its noise about a line over all of it, not none (a
            # noise of zero put every sample of the rest out of it, and the end of
            # motion at the record's last sample)
            sigma_x = block_noise(t, x, after, size) or block_noise(t, x, after, n - tail_start)
            sigma_x = sigma_x or 0.0
            sigma_x = max(sigma_x, 1e-8 * float(np.ptp(x)))
            out_x = np.flatnonzero(
                np.abs(x[lo:hi] - np.median(rest_x)) > DISPLACEMENT_THRESHOLD * sigma_x
            )
            if out_x.size:
                i = lo + int(out_x[-1])
                stop_time = float(t[min(n - 1, i + 1)])
                stop_index = int(np.searchsorted(t, stop_time, side="right")) - 1
                out = out[:0]
        if by_steps:
            xp = np.asarray(periodic, dtype=float)
            tail = xp[tail_start : min(n, tail_start + size)]
            rest_level = float(np.median(tail))
            if np.mean(tail != rest_level) <= STEADY_REST:  # a rest on its step
                off = np.flatnonzero(xp[lo:hi] != rest_level)
                if off.size:
                    i = min(n - 1, lo + int(off[-1]) + 1)
                    stop_time = float(t[i])
                    stop_index = i
                out = out[:0]
        by_velocity = velocity_alone and displacement is None and not by_steps
        if by_velocity and not out.size:
            # no excursion near the last coherent block: the swings sank below the
            # threshold more than a block before the oscillation did
            base = int(starts[first])
            out = base - lo + np.flatnonzero(np.abs(v[base:lo] - level) > level_cut)
        if out.size:
            i = lo + int(out[-1])
            stop_time = _root(t, v, level, max(0, i + 1 - fit_len), i + 1 - skip, i)
            if stop_time is None or not t[max(0, i - skip)] <= stop_time <= t[min(n - 1, i + skip)]:
                stop_time = float(t[i])  # within a sample of the last excursion
            stop_index = int(np.searchsorted(t, stop_time, side="right")) - 1
        if by_velocity and stop_index is not None:
            fade_time = _fade_time(t, v, stop_index, size, period, tail_start)
        if by_velocity and fade_time is None and stop_index is not None:
            later = _missed_alone(t, v, stop_index, stop_time, level, sigma, size)
            if later is not None:
                stop_index, stop_time = later
        if recorded and beside is not None and stop_index is not None:
            later = _missed_half_cycle(
                t,
                v,
                np.asarray(beside, dtype=float),
                stop_index,
                stop_time,
                level,
                sigma,
                size,
            )
            if later is None and fade_time is None:
                # the displacement's turning point within its threshold of the rest (a
                # last half cycle on the same side, from between x_c and 2x_c to its
                # rest): the velocity's lobe alone, as a velocity recorded alone
                later = _missed_alone(t, v, stop_index, stop_time, level, sigma, size)
            if later is not None:
                stop_index, stop_time = later
        if stop_index is not None:
            rest = stop_index + 1 if fade_time is None else tail_start
            quiet[rest + max(1, size // 8) :] = True
    elif moving[-1] and recorded:
        # a rest after the stop shorter than a block (the last block holds the last
        # swings): a last eighth of a period within the threshold of its median, and
        # after the last excursion beyond it no more spread than the noise's (a
        # recorded velocity's: a derivative's smoothed noise spreads less than its σ
        # at two periods, and a decay that fades would be taken for a stop)
        level = float(np.median(v[n - fit_len :]))
        out = np.flatnonzero(np.abs(v[int(starts[last]) :] - level) > level_cut)
        if out.size:
            i = int(starts[last]) + int(out[-1])
            if n - 1 - i >= fit_len and _still(v[i + 1 + skip :], sigma):
                stop_time = _root(t, v, level, max(0, i + 1 - fit_len), i + 1 - skip, i)
                if stop_time is None or not t[max(0, i - skip)] <= stop_time <= t[i + skip]:
                    stop_time = float(t[i])
                stop_index = int(np.searchsorted(t, stop_time, side="right")) - 1
                quiet[stop_index + 1 + max(1, size // 8) :] = True
    # Release: refined near the first moving block only.
    release_index = release_time = None
    out = np.zeros(0, int)
    base = head_end
    hi = min(n, int(starts[first]) + 2 * size)
    if head_end >= size // 2 and not moving[0]:
        lo = max(0, head_end - size)
        level = float(np.median(v[lo:head_end]))
        excursion = np.abs(v[head_end:hi] - level)
        out = np.flatnonzero(excursion > level_cut)
        if (
            out.size
            and 2.0 * level_cut > float(np.max(excursion))
            and _few_levels(periodic, COARSE_LEVELS)
        ):
            # a threshold beyond half the first swings (a coarse velocity whose rest
            # toggles, its σ near half a step) is crossed late, if at all: the
            # displacement's levels place the release (below)
            out = out[:0]
    elif moving[0] and recorded:
        # a rest before the release shorter than a block (the first block holds the
        # first swings): a first eighth of a period within the threshold of its median,
        # and before the first excursion beyond it no more spread than the noise's
        level = float(np.median(v[:fit_len]))
        base = 0
        out = np.flatnonzero(np.abs(v[:hi] - level) > level_cut)
        if out.size and (out[0] < fit_len or not _still(v[: int(out[0]) - skip], sigma)):
            out = out[:0]
    elif velocity_alone and moving[0]:
        # a rest shorter than a period before the release (a velocity alone, whose
        # integral's wander there would give turning points): a first quarter period
        # within the threshold of its median, then the first excursion beyond it (a
        # record that starts in motion leaves the median within a quarter period)
        head = max(fit_len, round(0.25 * period / dt))
        level = float(np.median(v[:head]))
        base = 0
        out = np.flatnonzero(np.abs(v[:hi] - level) > level_cut)
        if out.size and out[0] < head:
            out = out[:0]
    if out.size:
        i = base + int(out[0])
        release_time = _root(t, v, level, i + skip, min(n, i + fit_len), i)
        if (
            release_time is None
            or not t[max(0, i - skip)] <= release_time <= t[min(n - 1, i + skip)]
        ):
            release_time = float(t[max(0, i - 1)])
        release_index = int(np.searchsorted(t, release_time, side="right")) - 1
    elif head_end >= size // 2 and not moving[0] and _few_levels(periodic):
        # no velocity excursion beyond the threshold: a coarse velocity whose rest
        # toggles between two levels (dither) has its σ near half a step, and eight of
        # them can exceed its whole swing; the displacement's levels place the release
        lo = max(0, head_end - size)
        release_index = _release_from_levels(np.asarray(periodic, dtype=float), lo, head_end, hi)
        if release_index is not None:
            release_time = float(t[release_index])
    if release_index is not None:
        quiet[: max(0, release_index - max(1, size // 8))] = True
    return MotionSpan(
        release_index=release_index,
        release_time=release_time,
        stop_index=stop_index,
        stop_time=stop_time,
        quiet=quiet,
        noise=sigma,
        threshold=level_cut,
        block=size,
        fade_time=fade_time,
        bounds=bounds,
        others=others,
    )


def _separate_motions(
    t: NDArray,
    moving: NDArray,
    var1: NDArray,
    var2: NDArray,
    starts: NDArray,
    size: int,
    first: int,
    last: int,
) -> tuple[tuple[int, int] | None, tuple[tuple[float, float], ...]]:
    """The samples around the motion of blocks ``first`` to ``last`` that hold no other
    motion (:data:`SEPARATE_MOTION`), and the other motions' spans [s]; ``(None, ())``
    where there is none. ``var1``, ``var2``: each block's variance about its mean and
    about the fitted oscillation. Two runs of moving blocks are separate motions only
    where a block between them is quiet (its whole variance within the same tenth of the
    largest oscillation): a motion that changes its frequency (a drive let go into the
    free decay) is not coherent at one period across the change, but it is no rest."""
    amp = np.sqrt(np.clip(var1 - var2, 0.0, None))
    spread = np.sqrt(np.clip(var1, 0.0, None))
    largest = float(np.max(amp[first : last + 1]))
    n = t.size
    lo, hi = 0, n
    others: list[tuple[float, float]] = []
    i = 0
    while i < moving.size:
        if not moving[i] or first <= i <= last:
            i += 1
            continue
        j = i
        while j + 1 < moving.size and moving[j + 1]:
            j += 1
        gap = spread[j + 1 : first] if j < first else spread[last + 1 : i]
        quiet_between = gap.size > 0 and float(np.min(gap)) <= SEPARATE_MOTION * largest
        if j > i and quiet_between and float(np.max(amp[i : j + 1])) >= SEPARATE_MOTION * largest:
            others.append((float(t[starts[i]]), float(t[min(n - 1, int(starts[j]) + size - 1)])))
            # the time between two motions holds the rig made ready again (a magnet
            # pulling the mass back to its hold): the rest beside this motion is taken
            # up to REST_BESIDE blocks from it, which its noise needs at most
            if j < first:
                lo = max(lo, int(starts[j]) + size, int(starts[first]) - REST_BESIDE * size)
            else:
                hi = min(hi, int(starts[i]), int(starts[last]) + (1 + REST_BESIDE) * size)
        i = j + 1
    if not others or hi - lo < size:
        return None, ()
    return (lo, hi), tuple(others)


#: Largest ratio of the standard deviations of a quiet block's quarters (each about its
#: line), the largest to their median, for the block to be rest: a quarter holding a
#: few hundredths of a second of a swing has ten times the others'.
QUARTER_SPREAD = 4.0


def _holds_motion(t: NDArray, v: NDArray, start: int, size: int) -> bool:
    """Whether the block of ``size`` samples from ``start`` holds motion at one end: one
    of its quarters spreads beyond :data:`QUARTER_SPREAD` times their median."""
    quarter = size // 4
    if quarter < 4:
        return False
    var1, _ = _block_fits(t, v, start + quarter * np.arange(4), quarter, 0.0)
    return bool(np.max(var1) > QUARTER_SPREAD**2 * np.median(var1))


#: Largest standard deviation, in rest noise standard deviations, of a stretch shorter
#: than a block taken for rest (white noise's over 40 samples exceeds 1.5 σ with
#: probability below 1e-4; an oscillation of 1.5 σ in amplitude has 1.35 σ).
REST_SPREAD = 1.5


def _still(segment: NDArray, sigma: float) -> bool:
    """Whether ``segment`` (an eighth of a period at least, minus the samples next to a
    crossing) spreads about its mean by at most :data:`REST_SPREAD` noise σ: a rest,
    not an oscillation under the threshold."""
    return segment.size >= 8 and float(np.std(segment)) <= REST_SPREAD * sigma


def _few_levels(x: ArrayLike | None, most: int = 0) -> bool:
    """Whether ``x`` is a displacement on at most ``most`` levels (default
    :data:`FEW_LEVELS`)."""
    limit = most or FEW_LEVELS
    return x is not None and np.unique(np.asarray(x, dtype=float)).size <= limit


def _release_from_levels(x: NDArray, lo: int, head_end: int, hi: int) -> int | None:
    """Release of a quantised displacement ``x`` from its levels, or None.

    ``x[lo:head_end]`` is rest (on one level, or toggling between neighbouring levels
    by its noise), ``x[head_end:hi]`` holds the start of the motion. The motion leaves
    the levels the rest occupies; the release is the last sample before that on the
    rest's own level (its median): within the time the motion takes to fall by a step
    from the held position, the resolution the levels give.
    """
    head = x[lo:head_end]
    low, high = float(np.min(head)), float(np.max(head))
    span = x[head_end:hi]
    beyond = np.flatnonzero((span < low) | (span > high))
    if not beyond.size:
        return None
    leaves = head_end + int(beyond[0])
    on_level = np.flatnonzero(x[lo:leaves] == float(np.median(head)))
    return lo + int(on_level[-1]) if on_level.size else None


def _fade_time(
    t: NDArray, v: NDArray, stop_index: int, size: int, period: float, tail_start: int
) -> float | None:
    """Where the oscillation ends when it fades into the noise after ``stop_index``:
    ``t[tail_start]``, the end of the last coherent block, when the block after the
    stop (two periods, or what the record holds of them, one period at least) holds a
    coherent oscillation at the rig's frequency (:data:`COHERENCE`, as a moving block);
    None when it does not (the motion stopped: after a dry-friction stop the velocity
    is the rest's noise)."""
    after = stop_index + 1
    length = min(size, v.size - after)
    if length < size // 2 or tail_start <= after:
        return None
    var1, var2 = _block_fits(
        t[after : after + length],
        v[after : after + length],
        np.zeros(1, int),
        length,
        2.0 * math.pi / period,
    )
    if not var1[0] > 0 or 1.0 - var2[0] / var1[0] <= COHERENCE:
        return None
    return float(t[tail_start])


def check_turning_points(
    times: ArrayLike,
    half_period: float,
    *,
    tolerance: float = 0.3,
    timing_sd: ArrayLike | None = None,
) -> None:
    """Refuse turning points that are not half a period apart.

    Consecutive turning points of a free decay are π/ω_d apart (Eq. 13) whatever the
    friction (the Coulomb force only shifts the centre of each half cycle); a wiggle of
    the noise counted as a turning point, or a missed one, breaks that.

    Parameters
    ----------
    times : array_like
        Turning-point times [s], increasing.
    half_period : float
        The damped half-period [s].
    tolerance : float
        Largest accepted relative deviation of an interval from ``half_period``.
    timing_sd : array_like, optional
        Standard deviation of each turning-point time from the noise [s]: an interval
        may also be off by 6 times the sum of its ends' (a turning point barely out of
        the noise is timed poorly, not wrongly).

    Raises
    ------
    RecordingError
        "turning points: ..." naming the first interval off and by how much.
    """
    tt = np.asarray(times, dtype=float)
    gaps = np.diff(tt)
    allowed = np.full(gaps.shape, tolerance * half_period)
    if timing_sd is not None:
        sd = np.asarray(timing_sd, dtype=float)
        allowed = allowed + 6.0 * (sd[:-1] + sd[1:])
    off = np.flatnonzero(np.abs(gaps - half_period) > allowed)
    if off.size:
        k = int(off[0])
        raise RecordingError(
            f"turning points: turning points {k} and {k + 1} (t = {tt[k]:.6g} s and "
            f"{tt[k + 1]:.6g} s) are {gaps[k]:.4g} s apart, not about half a period "
            f"({half_period:.4g} s ± {allowed[k]:.3g} s): a wiggle of the noise taken "
            "for a turning point, or a turning point missed"
        )


@dataclass(frozen=True)
class RegularTurningPoints:
    """Where the turning points of a record become half a period apart.

    Attributes
    ----------
    start : int
        The first turning point of the regular run: every interval from it on is half
        a period apart within the tolerance; 0 when the whole record is regular.
    half_period : float
        The damped half period of the regular run [s] (weighted least-squares slope of
        its turning times against their index, weights the turning points' values).
    times : ndarray
        All the turning times [s].
    allowed : ndarray
        The deviation from ``half_period`` accepted for each interval [s].
    faded : int or None
        Where the decay fades into the noise: the count of turning points kept, those
        after it (swings within ``fade_level``, off the half period) left out; None when
        none was.
    """

    start: int
    half_period: float
    times: NDArray
    allowed: NDArray
    faded: int | None = None

    @property
    def gaps(self) -> NDArray:
        """Intervals between consecutive turning points [s]."""
        return np.diff(self.times)

    @property
    def off(self) -> NDArray:
        """Indices k of the intervals (turning points k to k + 1) off the half period."""
        return np.flatnonzero(np.abs(self.gaps - self.half_period) > self.allowed)

    def describe(self, intervals: ArrayLike | None = None) -> str:
        """The spacing of the intervals ``intervals`` (default: those off), one clause
        each: "turning points k and k + 1 (t = … s and … s) are … s apart"; then the
        half period they are held to [s]."""
        gaps = self.gaps
        ks = self.off if intervals is None else np.asarray(intervals, dtype=int)
        half = self.half_period
        said = [
            f"turning points {k} and {k + 1} (t = {self.times[k]:.6g} s and "
            f"{self.times[k + 1]:.6g} s) are {gaps[k]:.4g} s apart ({gaps[k] / half:.2f} "
            f"half periods, ± {self.allowed[k] / half:.2f} accepted)"
            for k in ks.tolist()
        ]
        if not said:
            return f"all intervals are half a period ({half:.4g} s) apart"
        return "; ".join(said) + f", not about half a period ({half:.4g} s)"


def _slope(times: NDArray, weights: NDArray) -> float:
    """Weighted least-squares slope of ``times`` against their index [s]."""
    n = np.arange(times.size, dtype=float)
    w = weights if np.any(weights > 0) else np.ones_like(weights)
    return float(np.polyfit(n, times, 1, w=w)[0])


def _held(
    tt: NDArray, weights: NDArray, sd: NDArray | None, tolerance: float, start: int
) -> RegularTurningPoints:
    """The turning times ``tt`` held to the half period of the run from ``start``."""
    half = _slope(tt[start:], weights[start:])
    allowed = np.full(tt.size - 1, tolerance * abs(half))
    if sd is not None:
        allowed = allowed + 6.0 * (sd[:-1] + sd[1:])
    return RegularTurningPoints(start, half, tt, allowed)


def _settled(
    found: RegularTurningPoints, weights: NDArray, sd: NDArray | None, tolerance: float
) -> RegularTurningPoints:
    """``found`` started past the leading turning points of its run that the run does
    not continue: the cubic in n through the next :data:`SETTLE_POINTS` turning times
    (a period that changes smoothly with the amplitude is followed) misses the first
    by more than :data:`SETTLE` half periods and 6 times its timing noise (the last
    turning point of a drive, within the tolerance but off by 10 % of a half period,
    would bias the frequency by 1e-4)."""
    tt = found.times
    start = found.start
    moved = False
    while tt.size - start > SETTLE_POINTS:
        n = np.arange(1, SETTLE_POINTS + 1, dtype=float)
        near = tt[start + 1 : start + 1 + SETTLE_POINTS]
        cubic = np.polyfit(n, near - tt[start + 1], 3)
        miss = abs(tt[start] - tt[start + 1] - float(np.polyval(cubic, 0.0)))
        limit = SETTLE * abs(found.half_period) + (0.0 if sd is None else 6.0 * sd[start])
        if miss <= limit:
            break
        start += 1
        moved = True
    return _held(tt, weights, sd, tolerance, start) if moved else found


def regular_turning_points(
    times: ArrayLike,
    values: ArrayLike,
    *,
    tolerance: float = SPACING_TOLERANCE,
    timing_sd: ArrayLike | None = None,
    fade_level: float | None = None,
) -> RegularTurningPoints:
    """The run of turning points half a period apart that ends the record.

    Consecutive turning points of a free decay are π/ω_d apart (Eq. 13). A record's
    first turning points may not be: a pendulum released at 135° swings with a period
    half as long again as its small swings' (the restoring force sin θ), and an
    oscillator set going by a hand or a blow is driven for its first cycles. Those are
    real turning points, not of the free decay at one frequency: the analysis starts
    after them, where the spacing becomes regular (as it does after clipped cycles).

    The half period is the slope of the turning times against their index (weighted by
    the values' size, as :attr:`bayestribo.signal.peaks.Peaks.half_period`), first
    over all the turning points; while an interval is off it by more than
    ``tolerance`` (and 6 times its ends' timing noise), the start moves past the last
    interval off and the half period is taken again over the turning points from
    there, until every interval from the start on is regular.

    Parameters
    ----------
    times : array_like
        Turning-point times [s], increasing.
    values : array_like
        The turning points' values about the equilibrium [signal unit] (weights).
    tolerance : float
        Largest accepted relative deviation of an interval from the half period.
    timing_sd : array_like, optional
        Standard deviation of each turning-point time from the noise [s]: an interval
        may also be off by 6 times the sum of its ends'.
    fade_level : float, optional
        Swing [signal unit] within which a turning point is in the noise's reach: where
        the turning points from the first such one on break the spacing of those before
        it (at least :data:`REGULAR_RUN` + 1 of them), the decay has faded into the
        noise, and they are left out (:attr:`RegularTurningPoints.faded`) instead of
        refusing the record. None: never.

    Returns
    -------
    RegularTurningPoints

    Raises
    ------
    RecordingError
        "turning points: ..." when an interval off the half period follows
        :data:`REGULAR_RUN` regular intervals (two oscillations): inside the decay,
        it is a wiggle of the noise taken for a turning point or a turning point
        missed, as :func:`check_turning_points` says; or when fewer than two turning
        points are regular.
    """
    tt = np.asarray(times, dtype=float)
    w = np.abs(np.asarray(values, dtype=float))
    if tt.size < 2:
        raise RecordingError(
            f"turning points: {tt.size} found; at least 2 are needed for the half period"
        )
    sd = None if timing_sd is None else np.asarray(timing_sd, dtype=float)
    faded = None if fade_level is None else _faded(tt, w, sd, tolerance, fade_level)
    if faded is not None:
        tt, w = tt[:faded], w[:faded]
        sd = None if sd is None else sd[:faded]
    found = _regular(tt, w, sd, tolerance)
    return found if faded is None else replace(found, faded=faded)


def _faded(
    tt: NDArray, w: NDArray, sd: NDArray | None, tolerance: float, fade_level: float
) -> int | None:
    """The count of turning points before the decay fades into the noise: the first
    turning point whose swing is within ``fade_level``, where an interval from the one
    before it on is off the half period of the turning points before it; None when
    the spacing holds (or too few turning points come before it to say)."""
    low = np.flatnonzero(w <= fade_level)
    if low.size == 0:
        return None
    m = int(low[0])
    if m < REGULAR_RUN + 1:
        return None
    head = _held(tt[:m], w[:m], None if sd is None else sd[:m], tolerance, 0)
    gaps = np.diff(tt[m - 1 :])
    allowed = np.full(gaps.size, tolerance * abs(head.half_period))
    if sd is not None:
        allowed = allowed + 6.0 * (sd[m - 1 : -1] + sd[m:])
    if np.any(np.abs(gaps - head.half_period) > allowed):
        return m
    return None


def _regular(tt: NDArray, w: NDArray, sd: NDArray | None, tolerance: float) -> RegularTurningPoints:
    """:func:`regular_turning_points` of turning points that do not fade."""
    found = _held(tt, w, sd, tolerance, 0)
    while True:
        off = found.off
        off = off[off >= found.start]
        if off.size == 0:
            break
        start = int(off[-1]) + 1
        if tt.size - start < 2:
            raise RecordingError(
                f"turning points: {found.describe(off)}: no two consecutive turning points "
                "are half a period apart after them (is the record of a free decay?)"
            )
        found = _held(tt, w, sd, tolerance, start)
    if found.start == 0:
        return found
    found = _settled(found, w, sd, tolerance)
    # the irregular intervals are the record's start only when no two oscillations of
    # regular ones come before one of them; else one is inside the decay
    off = found.off
    regular = np.ones(found.start, dtype=bool)
    regular[off[off < found.start]] = False
    run = 0
    for k in range(found.start):
        if regular[k]:
            run += 1
            continue
        if run >= REGULAR_RUN:
            first = k - run
            raise RecordingError(
                f"turning points: {found.describe([k])}, after {run} regular intervals "
                f"from turning point {first} (t = {tt[first]:.6g} s): a wiggle of the "
                "noise taken for a turning point, or a turning point missed; if the "
                "motion before it is not the free decay (a start still driven, large "
                f"swings), skip the {k + 1} turning points up to it"
            )
        run = 0
    return found
