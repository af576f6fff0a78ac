"""Peaks flattened at the largest swings: a sensor that saturates (soft clipping).

A sensor driven beyond its linear range does not always cut the signal flat (which
:func:`bayestribo.io.validation.validate_run` refuses when a file is read): an
amplifier or a vibrometer that saturates softly reads ``L tanh(x/L)``, a smooth signal
whose largest swings are compressed. The energy decay then starts low and the fit
reads the compression as damping.

At a turning point the displacement of a linear oscillator bends with the curvature
|x''| = ω²|Y| (Coulomb friction moves the centre of each half cycle by ±x_c, which a
fit symmetric about the turning point averages out; what remains of it, and the
fitting window's own bias, make the relation a line K = b|Y| - d). A saturated
reading bends less at its largest swings: ``L tanh(x/L)`` has the curvature
``sech²(A/L)`` times the true one at a true swing A, a deficit of 5 % against the line
at A = 0.28 L, where the swing itself reads 2.5 % low.

:func:`flattened_turning_points` fits that line to the turning points of the smaller
half of the swings and counts the leading turning points (the largest swings, at the
start of a free decay) whose curvature falls short of it by more than
:data:`MAX_DEFICIT` of it and by more than :data:`MIN_Z` times the scatter of the
reference turning points about it, when there are at least :data:`MIN_FLATTENED`,
and whose curvature per unit swing, K/|Y|, also falls below the reference turning
points' median by more than :data:`MIN_FALL`. The last condition keeps a friction that
grows towards zero speed (Stribeck friction) from passing for a clip: near a turning
point the mass arrives faster than it leaves, so the excess acts longer after the turn
than before, the two sides' friction no longer cancel, and the curvature of the small
swings, where the excess is comparable to the spring's force, falls below ω²|Y|
(by 5-30 % at the last turning points of a record with a 0.3 m/s² excess at 5 Hz).
The line drawn through them is then steeper than ω², and the largest swings, whose
K/|Y| is the linear oscillator's, fall 5-12 % short of it; a saturation instead lowers
K/|Y| at the largest swings below the smaller ones'.
:func:`bayestribo.signal.decay.energy_decay` applies it to a recorded displacement at
its turning points and to a recorded velocity at its extremes (one between each two
turning points, where v'' = -ω²v whatever the friction), leaves the flattened ones out
of the analysis with a :class:`~bayestribo.errors.ClippingWarning`, or refuses the
record when too few turning points remain. A spring that softens with the swing bends
the displacement less at large swings too: the message names both causes.

A saturation so deep that the smaller half of the swings is compressed as much as the
largest (a range below a quarter of the largest swing) leaves no line to compare
with, and is not found.

**Hard clipping** (a signal cut flat at the sensor's range) is told from the extreme of
a quantised signal by :func:`hard_clips`. A smooth extreme of swing A quantised in
steps q dwells on its last level while ``A(1 - cos ωs) < q``, for about
``sqrt(2q/A)/π`` of a period (:func:`expected_dwell`; 0.1 mm steps on an 8 cm swing at
1.35 Hz and 200 Hz: 2.4 samples, 1 cm steps: 23 samples), and it is entered by a
step of about one quantum. A cut is held for as long as the swing stays beyond it and
is entered with the signal's slope: a run at the signal's extreme value is a clip only
when it is longer than twice the expected dwell (and more than two samples) and both
its entry and its exit over two samples are larger than what a smooth extreme allows
there (``A(2ωh)²/2``, h the sample spacing, plus two quanta). Each such run is one
clipped cycle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "MAX_DEFICIT",
    "MIN_FALL",
    "MIN_FLATTENED",
    "MIN_SPAN",
    "MIN_TURNING_POINTS",
    "MIN_Z",
    "Flattening",
    "HardClip",
    "expected_dwell",
    "flattened_turning_points",
    "hard_clips",
    "quantum",
]

#: Relative curvature deficit [-] beyond which a turning point is flattened. A damping
#: that grows with the swing (ζ = 0.01 + 20 a at a = 1.5 mm) made 4.6 % at the largest
#: swings, the disturbed release of a noisy 1 kHz record 3.3 % at the first two.
MAX_DEFICIT = 0.05
#: Fewest leading turning points flattened for a record to count as clipped (one or two
#: are the release's disturbance, which the skipped first oscillation takes care of).
MIN_FLATTENED = 3
#: ... and beyond this many standard deviations of the reference turning points'
#: curvatures about the line (1.4826 times their median absolute deviation).
MIN_Z = 6.0
#: Fewest turning points the check needs (a line and its scatter from the smaller half).
MIN_TURNING_POINTS = 8
#: ... and whose curvature per unit swing K/|Y| falls short of the reference turning
#: points' median by more than this [-]: a saturation's does by about its deficit
#: (sech²(A/L) against tanh(A/L)/(A/L)); the larger swings of a friction that grows
#: towards zero speed keep theirs while the smallest swings' falls.
MIN_FALL = MAX_DEFICIT / 2
#: Least span of the smaller half's swings, as a fraction of the largest swing, to draw
#: the line through (a record that hardly decays is not checked).
MIN_SPAN = 0.2


@dataclass(frozen=True)
class Flattening:
    """The curvature of a signal's turning points against a linear oscillator's.

    Attributes
    ----------
    count : int
        Leading turning points whose curvature falls short (the largest swings); 0
        when fewer than :data:`MIN_FLATTENED` do.
    deficit : ndarray
        Relative curvature deficit of each turning point [-]: 1 - K/(b|Y| - d); 0.05
        for a curvature 5 % below the line.
    scatter : float
        Robust standard deviation of the reference turning points' curvatures about
        the line [signal unit/s²].
    level : float
        Smallest swing |Y| among the flattened turning points [signal unit]; nan when
        none is.
    """

    count: int
    deficit: NDArray
    scatter: float
    level: float


def _curvatures(t: NDArray, s: NDArray, index: NDArray, half_width: int) -> NDArray:
    """|s''| at each sample in ``index`` [signal unit/s²]: a least-squares parabola over
    the samples ``index ± half_width`` (as the turning points are refined).

    The windows of full width are fitted together, from the normal equations in the
    offsets scaled to [-1, 1] (the conditioning of :func:`numpy.polyfit`'s scaled
    columns; the same curvatures to about 1e-12), by einsum: 58 fits of 5,113 samples
    at 1 MHz took 25 ms one by one, most of it a threaded BLAS waiting for a busy core.
    A window cut by an end of the record is fitted alone.
    """
    index = np.asarray(index, dtype=int)
    out = np.full(index.size, np.nan)
    full = (index >= half_width) & (index <= s.size - 1 - half_width)
    if half_width >= 1 and full.any():
        centre = index[full]
        offsets = np.arange(-half_width, half_width + 1)
        tt = t[centre[:, None] + offsets] - t[centre][:, None]
        scale = np.maximum(np.abs(tt).max(axis=1, keepdims=True), np.finfo(float).tiny)
        u = tt / scale
        ss = s[centre[:, None] + offsets]
        powers = [np.ones_like(u), u, u * u, u * u * u, (u * u) * (u * u)]
        moments = np.stack([np.einsum("ij->i", p) for p in powers], axis=1)
        right = np.stack([np.einsum("ij,ij->i", p, ss) for p in powers[:3]], axis=1)
        gram = np.stack(
            [moments[:, 0:3], moments[:, 1:4], moments[:, 2:5]], axis=1
        )  # Σ u^(a+b) for a, b in 0..2
        c2 = np.linalg.solve(gram, right[..., None])[:, 2, 0] / (scale[:, 0] ** 2)
        out[np.flatnonzero(full)] = np.abs(2.0 * c2)
    for j in np.flatnonzero(~full).tolist():
        i = int(index[j])
        w = min(half_width, i, s.size - 1 - i)
        if w < 1:
            continue
        tt = t[i - w : i + w + 1] - t[i]
        c2 = np.polyfit(tt, s[i - w : i + w + 1], 2)[0]
        out[j] = abs(2.0 * c2)
    return out


def flattened_turning_points(
    t: NDArray, s: NDArray, index: NDArray, value: NDArray, half_width: int
) -> Flattening | None:
    """Count the leading turning points of ``s`` flattened at their peaks.

    Parameters
    ----------
    t : ndarray
        Sample times [s].
    s : ndarray
        The signal (displacement, any length unit).
    index : ndarray of int
        Sample index of each turning point, in time order.
    value : ndarray
        Each turning point's value about the equilibrium [signal unit], alternating in
        sign.
    half_width : int
        Samples on each side of a turning point its curvature is fitted over (the
        peak refinement's: about 1/12 of a period).

    Returns
    -------
    Flattening or None
        None with fewer than :data:`MIN_TURNING_POINTS` turning points, swings of the
        smaller half spanning less than :data:`MIN_SPAN` of the largest, or a line that
        cannot be fitted.
    """
    index = np.asarray(index, dtype=int)
    swing = np.abs(np.asarray(value, dtype=float))
    if index.size < MIN_TURNING_POINTS or index.size != swing.size:
        return None
    curvature = _curvatures(t, s, index, max(1, int(half_width)))
    usable = np.isfinite(curvature) & (swing > 0)
    reference = usable & (swing <= np.median(swing[usable])) if usable.any() else usable
    if np.count_nonzero(reference) < MIN_TURNING_POINTS // 2:
        return None
    if np.ptp(swing[reference]) < MIN_SPAN * float(np.max(swing[usable])):
        return None  # swings too alike to draw the line through (no decay to speak of)
    b, d = np.polyfit(swing[reference], curvature[reference], 1)
    if not (b > 0 and math.isfinite(d)):
        return None
    line = b * swing - d
    with np.errstate(divide="ignore", invalid="ignore"):
        deficit = np.where(usable & (line > 0), 1.0 - curvature / line, 0.0)
    # the curvature's noise (from the signal's noise over the fitting window) does not
    # grow with the swing: the scatter is taken in curvature, not relative to it
    short = np.where(usable, line - curvature, 0.0)
    spread = short[reference]
    scatter = 1.4826 * float(np.median(np.abs(spread - np.median(spread))))
    # a saturation lowers the curvature per unit swing at the largest swings below the
    # smaller swings' own; a friction that grows towards zero speed (Stribeck) lowers
    # it at the smallest swings instead, which bends the line drawn through them and
    # leaves the largest swings short of it at their full curvature per unit swing
    with np.errstate(divide="ignore", invalid="ignore"):
        per_swing = np.where(usable, curvature / swing, np.nan)
    fall = 1.0 - per_swing / float(np.median(per_swing[reference]))
    flattened = (deficit > MAX_DEFICIT) & (short > MIN_Z * scatter) & (fall > MIN_FALL)
    count = int(np.argmin(flattened)) if not flattened.all() else int(flattened.size)
    if count < MIN_FLATTENED:
        count = 0
    level = float(np.min(swing[:count])) if count else math.nan
    return Flattening(count, deficit, scatter, level)


@dataclass(frozen=True)
class HardClip:
    """A signal cut flat at one of its extremes (:func:`hard_clips`).

    Attributes
    ----------
    kind : str
        ``"maximum"`` or ``"minimum"``: which extreme is cut.
    level : float
        The value the signal is held at [signal unit].
    starts : ndarray of int
        First sample of each clipped run (one per clipped cycle).
    lengths : ndarray of int
        Samples in each clipped run.
    expected : float
        Samples a smooth quantised extreme of the signal's swing would dwell there.
    """

    kind: str
    level: float
    starts: NDArray
    lengths: NDArray
    expected: float

    @property
    def cycles(self) -> int:
        """Number of clipped cycles (runs)."""
        return int(self.starts.size)

    def times(self, t: NDArray) -> tuple[float, float]:
        """First and last clipped sample's time [s]."""
        last = int(self.starts[-1] + self.lengths[-1] - 1)
        return float(t[int(self.starts[0])]), float(t[last])

    def describe(self, name: str, t: NDArray) -> str:
        """One sentence naming the field, the level, the cycles and their times."""
        first, last = self.times(t)
        return (
            f"field {name!r} is clipped: it is held flat at its {self.kind} {self.level:.6g} in "
            f"{self.cycles} cycle(s) between t = {first:.6g} s and {last:.6g} s, for up to "
            f"{int(self.lengths.max())} samples (a smooth extreme of this swing and step "
            f"dwells about {self.expected:.1f})"
        )


def quantum(values: NDArray) -> float:
    """The smallest non-zero sample-to-sample change of ``values`` [signal unit] (0 when
    the signal is constant): its quantisation step, or less."""
    steps = np.abs(np.diff(values))
    steps = steps[steps > 0]
    return float(steps.min()) if steps.size else 0.0


def expected_dwell(swing: float, step: float, period: float, dt: float) -> float:
    """Samples a quantised sinusoid stays on its extreme level.

    Parameters
    ----------
    swing : float
        Amplitude A of the oscillation [signal unit].
    step : float
        Quantisation step q [signal unit].
    period : float
        Oscillation period [s].
    dt : float
        Sample spacing [s].

    Returns
    -------
    float
        ``period·sqrt(2q/A)/(π dt) + 1`` samples (the phase span where
        ``A(1 - cos φ) < q``; at least one sample).
    """
    if not (swing > 0 and period > 0 and dt > 0):
        return 1.0
    return period * math.sqrt(2.0 * min(max(step, 0.0), swing) / swing) / (math.pi * dt) + 1.0


def hard_clips(
    t: NDArray, values: NDArray, period: float, *, min_samples: int = 3
) -> list[HardClip]:
    """Runs of a signal held flat at its maximum or minimum that a smooth extreme is not.

    Parameters
    ----------
    t : ndarray
        Sample times [s], regular.
    values : ndarray
        The signal [any unit].
    period : float
        Oscillation period [s].
    min_samples : int
        Fewest samples of a clipped run, whatever the expected dwell.

    Returns
    -------
    list of HardClip
        One per clipped extreme (none for a smooth, quantised signal); runs that touch
        either end of the record (the rest before the release or after the stop) are
        not clips.
    """
    values = np.asarray(values, dtype=float)
    n = values.size
    if n < 8 or not (math.isfinite(period) and period > 0):
        return []
    dt = float(t[1] - t[0])
    q = quantum(values)
    centre = float(np.median(values))
    out = []
    for kind, level in (("maximum", float(values.max())), ("minimum", float(values.min()))):
        at = np.flatnonzero(values == level)
        if at.size < min_samples:
            continue
        breaks = np.flatnonzero(np.diff(at) > 1) + 1
        starts = at[np.r_[0, breaks]]
        stops = at[np.r_[breaks - 1, at.size - 1]] + 1
        swing = abs(level - centre)
        expected = expected_dwell(swing, q, period, dt)
        omega_h = 4.0 * math.pi * dt / period  # over two samples
        smooth_step = swing * omega_h * omega_h / 2.0 + 2.0 * q
        keep = []
        for a, b in zip(starts.tolist(), stops.tolist(), strict=True):
            if a < 2 or b > n - 2 or b - a < min_samples or b - a <= 2.0 * expected:
                continue
            # over two samples: a cut may be entered a fraction of its slope's step away
            entry, leave = abs(values[a - 2] - level), abs(values[b + 1] - level)
            if min(entry, leave) > smooth_step:
                keep.append((a, b - a))
        if keep:
            arr = np.array(keep, dtype=int)
            out.append(HardClip(kind, level, arr[:, 0], arr[:, 1], expected))
    return out
