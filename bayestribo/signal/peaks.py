"""Turning points (peaks) of a recorded free decay.

The peak-based estimators (Rigaud et al. 2010, section 1.5-1.6) need the successive
extrema Y_n of the displacement (or of the velocity, "using -Y'_k in place of Y_k"),
measured from the equilibrium position. On a real recording the extrema are noisy,
the signal has an unknown offset, the first oscillation may be disturbed by the
release, and with dry friction the motion stops and leaves a flat tail made of
noise only. :func:`find_peaks` handles these:

* the dominant period comes from the spectrum of the signal's first difference:
  among its strongest peaks, the one whose oscillation is the strongest in the signal
  itself (a mains line or the noise at Nyquist, gained by the difference, is not the
  oscillation; see :func:`~bayestribo.signal.period.dominant_period`); candidate
  extrema must be at least 0.6 period apart (same kind) and stand out of the noise (prominence);
* maxima and minima are forced to alternate (of two same-kind neighbours the more
  extreme one is kept);
* each extremum is refined to sub-sample precision by a least-squares parabola over
  ±1/12 period (relative bias of the value ≈ 3e-4 for a sinusoid, see
  :func:`_refine`);
* the rest tail (a stretch longer than one period where the signal stays inside a
  ±4σ band) ends the motion; in a decay without friction, the peaks whose
  peak-to-peak height falls below ``threshold`` noise standard deviations end it;
* the offset (equilibrium position) is estimated from the peaks themselves
  (:func:`estimate_offset`), because with dry friction the rest position is *not*
  the equilibrium (it can be anywhere in ±μ_s); with enough peaks a slow linear
  drift of the equilibrium is fitted too (real rigs creep: in the AppStat
  HarmOsc3 recording the equilibrium moves by about the friction displacement).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import scipy.signal
from numpy.typing import ArrayLike, NDArray

from bayestribo.errors import RecordingError
from bayestribo.signal.period import dominant_period, sample_step

__all__ = ["Peaks", "estimate_noise", "estimate_offset", "find_peaks", "prepare_signal"]

Kind = Literal["displacement", "velocity"]
_KINDS = ("displacement", "velocity")


@dataclass(frozen=True)
class Peaks:
    """Successive turning points of one signal, measured from its equilibrium.

    Parameters
    ----------
    t : ndarray
        Times of the extrema [s] (sub-sample).
    value : ndarray
        Extremum values minus ``offset`` [signal unit]; signs alternate.
    kind : {"displacement", "velocity"}
        Which signal the extrema come from. For velocity the estimators use -Y'_k
        in place of Y_k (paper, section 1.6).
    offset : float
        Equilibrium level at t = 0 subtracted from the raw signal [signal unit].
    drift : float
        Drift of the equilibrium [signal unit/s]: the equilibrium at time t is
        ``offset + drift * t``.
    noise : float
        Standard deviation of the measurement noise per sample [signal unit].
    index : ndarray of int, optional
        Sample index nearest to each extremum (-1 when not from a recording).
    stop_time : float or None
        Time [s] after which the signal is a flat rest tail, ``None`` if the motion
        goes on to the end of the recording.
    rest_value : float or None
        Level of the rest tail minus ``offset`` [signal unit].
    value_noise : float
        Standard deviation of one extremum value [signal unit] (smaller than
        ``noise`` thanks to the parabola fit).
    """

    t: NDArray
    value: NDArray
    kind: Kind = "displacement"
    offset: float = 0.0
    noise: float = 0.0
    drift: float = 0.0
    index: NDArray = field(default_factory=lambda: np.empty(0, dtype=int))
    stop_time: float | None = None
    rest_value: float | None = None
    value_noise: float = 0.0

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float)
        value = np.asarray(self.value, dtype=float)
        if t.ndim != 1 or t.shape != value.shape:
            raise RecordingError(
                f"peak times and values must be 1-D arrays of one length, got shapes "
                f"{t.shape} and {value.shape}"
            )
        if self.kind not in _KINDS:
            raise RecordingError(f"kind must be one of {_KINDS}, got {self.kind!r}")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "value", value)
        index = np.asarray(self.index, dtype=int)
        if index.size == 0:
            index = np.full(t.shape, -1, dtype=int)
        object.__setattr__(self, "index", index)

    def __len__(self) -> int:
        return int(self.t.size)

    @property
    def sign(self) -> NDArray:
        """Sign of each extremum about the equilibrium (+1 maximum, -1 minimum)."""
        return np.sign(self.value)

    @property
    def half_period(self) -> float:
        """Damped half-period π/(Ω√(1-ζ²)) [s]: weighted least-squares slope of t_n on n.

        The weights are the squared peak values: a displacement turning point joins
        two arcs of different curvature (centres ±μ_k), which shifts the symmetric
        parabola's vertex by about (3/8)(μ_k/|Y_n|) of the fit half-window, so small
        peaks are timed worse.
        """
        if len(self) < 2:
            raise RecordingError("at least 2 peaks are needed for the half-period")
        n = np.arange(len(self), dtype=float)
        w = np.abs(self.value)
        if not np.any(w > 0):
            w = np.ones_like(w)
        return float(np.polyfit(n, self.t, 1, w=w)[0])

    def amplitudes(self) -> NDArray:
        """Peak values as Y_k (displacement) or -Y'_k (velocity), paper section 1.6."""
        return -self.value if self.kind == "velocity" else self.value.copy()

    def skip(self, count: int) -> Peaks:
        """The same peaks without the first ``count`` ones."""
        if count < 0:
            raise RecordingError(f"skip must be >= 0, got {count}")
        return Peaks(
            t=self.t[count:],
            value=self.value[count:],
            kind=self.kind,
            offset=self.offset,
            noise=self.noise,
            drift=self.drift,
            index=self.index[count:],
            stop_time=self.stop_time,
            rest_value=self.rest_value,
            value_noise=self.value_noise,
        )


def prepare_signal(
    t: ArrayLike, signal: ArrayLike, name: str = "signal"
) -> tuple[NDArray, NDArray]:
    """Check a sampled signal: 1-D, same length as ``t``, finite, ``t`` increasing.

    Raises
    ------
    RecordingError
        Naming the argument and what was expected.
    """
    t, s, _ = _checked(t, signal, name)
    return t, s


def _checked(t: ArrayLike, signal: ArrayLike, name: str) -> tuple[NDArray, NDArray, NDArray]:
    """:func:`prepare_signal`'s arrays and the steps ``np.diff(t)`` it checked."""
    t = np.asarray(t, dtype=float)
    s = np.asarray(signal, dtype=float)
    if t.ndim != 1:
        raise RecordingError(f"t must be a 1-D array of times [s], got shape {t.shape}")
    if s.shape != t.shape:
        raise RecordingError(f"{name} must have the shape of t {t.shape}, got {s.shape}")
    if t.size < 16:
        raise RecordingError(f"{name}: at least 16 samples are needed, got {t.size}")
    if not np.all(np.isfinite(t)):
        raise RecordingError("t contains NaN or infinite values")
    bad = np.flatnonzero(~np.isfinite(s)) if not np.isfinite(s).all() else s[:0]
    if bad.size:
        raise RecordingError(
            f"{name} contains {bad.size} NaN or infinite values (first at sample {bad[0]})"
        )
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.flatnonzero(dt <= 0)[0])
        raise RecordingError(f"t must be strictly increasing; it is not at sample {i + 1}")
    return t, s, dt


def estimate_noise(signal: ArrayLike) -> float:
    """Standard deviation of white measurement noise from 4th differences (robust).

    σ = 1.4826 MAD(Δ⁴x)/√70: the 4th difference of white noise has variance 70σ²,
    while a sinusoid sampled at ≥ 20 points per period contributes less than
    (2π/20)⁴ ≈ 1 % of its amplitude.
    """
    s = np.asarray(signal, dtype=float)
    d4 = np.diff(s, n=4)
    if d4.size == 0:
        return 0.0
    mad = float(np.median(np.abs(d4 - np.median(d4))))
    return 1.4826 * mad / math.sqrt(70.0)


def _refine(t: NDArray, s: NDArray, i: int, half_width: int) -> tuple[float, float]:
    """Sub-sample extremum by a least-squares parabola over samples i ± half_width.

    For a sinusoid fitted over ±θ (θ = π/6 for ±1/12 period) the vertex value is
    biased by about (3/35)θ⁴/24 ≈ 2.7e-4 of the amplitude (projection of the θ⁴
    term on {1, θ²}); the position is unbiased by symmetry.
    """
    lo = max(0, i - half_width)
    hi = min(s.size, i + half_width + 1)
    w = min(i - lo, hi - 1 - i)
    lo, hi = i - w, i + w + 1
    if w < 1:
        return float(t[i]), float(s[i])
    tt = t[lo:hi] - t[i]
    c2, c1, c0 = np.polyfit(tt, s[lo:hi], 2)
    if c2 == 0.0:
        return float(t[i]), float(s[i])
    dt_v = -c1 / (2.0 * c2)
    if abs(dt_v) > abs(tt[-1]):
        return float(t[i]), float(s[i])
    return float(t[i] + dt_v), float(c0 - c1 * c1 / (4.0 * c2))


def _alternate(idx: NDArray, is_max: NDArray, s: NDArray) -> tuple[NDArray, NDArray]:
    """Keep maxima and minima alternating: of same-kind neighbours keep the extreme one."""
    keep_i: list[int] = []
    keep_m: list[bool] = []
    for i, m in zip(idx.tolist(), is_max.tolist(), strict=True):
        if keep_m and keep_m[-1] == m:
            j = keep_i[-1]
            if (m and s[i] > s[j]) or (not m and s[i] < s[j]):
                keep_i[-1] = i
            continue
        keep_i.append(i)
        keep_m.append(m)
    return np.asarray(keep_i, dtype=int), np.asarray(keep_m, dtype=bool)


#: Samples of the first block :func:`_rest_tail_start` examines from the record's end
#: (each further block twice the last).
_TAIL_BLOCK = 4096


def _rest_tail_start(s: NDArray, band: float, min_len: int) -> int | None:
    """First sample of the final stretch staying inside ±band of its median, if long enough.

    The tail grows backwards while its range (the largest sample from there on less
    the smallest) stays within 2·band: a range that only grows, so the stretch ends at
    the last sample outside it. The ranges are taken block by block from the end, each
    block's running extremes carried into the next, until a block holds that sample:
    the same extremes, and the same sample, as over the whole record, without reading
    the motion before the tail.
    """
    limit = 2.0 * band
    end = s.size
    size = _TAIL_BLOCK
    carried: tuple[float, float] | None = None
    start = 0
    while end > 0:
        part = s[max(0, end - size) : end][::-1]  # from the end backwards
        hi = np.maximum.accumulate(part)
        lo = np.minimum.accumulate(part)
        if carried is not None:
            np.maximum(hi, carried[0], out=hi)
            np.minimum(lo, carried[1], out=lo)
        inside = (hi - lo) <= limit
        if carried is None and not inside[0]:
            return None  # not even the last sample (a band that is not a number)
        if not inside.all():
            start = end - int(np.argmin(inside))  # past the last sample outside
            break
        carried = (float(hi[-1]), float(lo[-1]))
        end -= part.size
        size *= 2
    if s.size - start < min_len:
        return None
    return start


def estimate_offset(
    values: ArrayLike,
    times: ArrayLike | None = None,
    drift: bool = False,
    noise: float = 0.0,
    rel_error: float = 5e-4,
) -> tuple[float, float]:
    """Equilibrium level of alternating raw extrema p_n (viscous + Coulomb decay).

    With P_n = p_n - c the extrema about the equilibrium c, Eq. 20 gives
    P_{n+1} = -r P_n + b sgn(P_n) with r = exp(-βπ). Two consequences are used:

    * peak-to-peak heights h_n = |p_n - p_{n+1}| = |P_n| + |P_{n+1}| do not depend on
      c and obey h_{n+1} = r h_n - 2b: a straight-line fit gives r;
    * mid-points m_n = (p_n + p_{n+1})/2 = c + S_n/2 with S_{n+1} = -r S_n: a linear
      fit of m_n on (1, (-r)^n) gives c; with ``drift`` the equilibrium is
      c0 + c1 t and the fit is on (1, t_n', (-r)^n), t_n' the mid-point times.

    The same holds for velocity extrema (with another b), so this serves both. The
    fits are weighted by 1/√(noise² + (rel_error·h_n)²): a measured extremum carries
    the noise and an interpolation error proportional to its size (about 3e-4, see
    :func:`_refine`), which would otherwise swamp the small late extrema.

    Parameters
    ----------
    values : array_like
        Raw alternating extrema p_n [signal unit], at least 4 (6 with ``drift``).
    times : array_like, optional
        Their times [s]; needed with ``drift``.
    drift : bool
        Fit a linear drift of the equilibrium.
    noise : float
        Standard deviation of one extremum [signal unit].
    rel_error : float
        Relative error of one extremum from its interpolation.

    Returns
    -------
    level : float
        Equilibrium at t = 0 [signal unit].
    slope : float
        Drift [signal unit/s] (0 without ``drift``).
    """
    p = np.asarray(values, dtype=float)
    need = 6 if drift else 4
    if p.size < need:
        raise RecordingError(
            f"at least {need} alternating extrema are needed to locate the equilibrium"
            f"{' and its drift' if drift else ''}, got {p.size}"
        )
    h = np.abs(np.diff(p))
    sd = np.sqrt(noise**2 + (rel_error * h) ** 2)
    sd = np.where(sd > 0, sd, 1.0)
    r = float(h[-1] / h[0])
    if h.size >= 3:
        # h_{n+1} = r h_n - 2b by weighted least squares; heights that do not vary (a
        # coarse channel's swings, each a whole number of its steps) leave the slope
        # undetermined: the ratio of the mean heights is r then
        x = h[:-1]
        if np.ptp(x) > 1e-9 * np.max(x):
            r = float(np.polyfit(x, h[1:], 1, w=1.0 / sd[1:])[0])
        else:
            r = float(np.mean(h[1:]) / np.mean(x))
    # r outside (0, 1] only from noise on nearly undamped records: the mid-point fit
    # below stays well posed for any r, so r is used as fitted.
    m = 0.5 * (p[:-1] + p[1:])
    n = np.arange(m.size, dtype=float)
    basis = np.sign(-r) ** n * np.abs(r) ** n if r != 0 else (n == 0).astype(float)
    cols = [np.ones_like(m), basis]
    if drift:
        if times is None:
            raise RecordingError("estimate_offset: times are needed to fit a drift")
        tt = np.asarray(times, dtype=float)
        if tt.shape != p.shape:
            raise RecordingError(
                f"estimate_offset: times must have the shape of values {p.shape}, got {tt.shape}"
            )
        cols.append(0.5 * (tt[:-1] + tt[1:]))
    a = np.column_stack(cols) / sd[:, None]
    coef = np.linalg.lstsq(a, m / sd, rcond=None)[0]
    return float(coef[0]), float(coef[2]) if drift else 0.0


def find_peaks(
    t: ArrayLike,
    signal: ArrayLike,
    *,
    kind: Kind = "displacement",
    skip: int = 0,
    offset: float | Literal["auto", "constant"] | None = "auto",
    noise: float | None = None,
    threshold: float = 10.0,
    min_peaks: int = 3,
    period: float | None = None,
    rest_band: float | None = None,
) -> Peaks:
    """Find the successive extrema of a free-decay recording.

    Parameters
    ----------
    t : array_like
        Sample times [s], strictly increasing (near-uniform sampling).
    signal : array_like
        Displacement [length unit] or velocity [length unit/s] samples.
    kind : {"displacement", "velocity"}
        What ``signal`` is.
    skip : int
        Number of leading extrema to drop (e.g. 2 for the first oscillation,
        disturbed by the release; paper section 2.1).
    offset : float, "auto", "constant" or None
        Equilibrium level to subtract [signal unit]. "constant": from the extrema
        (:func:`estimate_offset`), or for a velocity with a rest tail the tail's
        median (the velocity is zero at rest). "auto": the same, plus a linear
        drift of a displacement's equilibrium when there are at least 8 extrema.
        ``None``: the signal is already centred (same as 0).
    noise : float, optional
        Noise standard deviation per sample [signal unit]; estimated from the
        signal (:func:`estimate_noise`) when omitted.
    threshold : float
        Extrema must stand ``threshold`` noise standard deviations above their
        neighbourhood (prominence) and the motion is considered over when a
        peak-to-peak height falls below it.
    min_peaks : int
        Fewest extrema accepted after skipping.
    period : float, optional
        Period of the oscillation [s] when the caller has it (the energy decay passes
        the whole record's :func:`~bayestribo.signal.period.dominant_period`, which
        sets its motion span, instead of a second estimate on the motion alone); by
        default the dominant period of ``signal``. It sets the least distance between
        extrema (0.6 period), the parabola's half-width (1/12 period) and the shortest
        rest tail (one period).
    rest_band : float, optional
        Half-width of the rest tail [signal unit]: the final stretch whose range stays
        within twice it, at least a period long, is the rest after the motion stops.
        By default four noise standard deviations; a coarsely quantised signal's caller
        gives a narrower one (a rest holds one or two neighbouring levels, a swing
        across three is motion: :func:`bayestribo.signal.decay.energy_decay`).

    Returns
    -------
    Peaks

    Raises
    ------
    RecordingError
        Bad arrays, no oscillation, fewer than ``min_peaks`` extrema, or a ``period``
        that is not a positive number.
    """
    if kind not in _KINDS:
        raise RecordingError(f"kind must be one of {_KINDS}, got {kind!r}")
    t, s, steps = _checked(t, signal, kind)
    if isinstance(skip, bool) or not isinstance(skip, int | np.integer) or skip < 0:
        raise RecordingError(f"skip must be an integer >= 0, got {skip!r}")
    if not (threshold > 0):
        raise RecordingError(f"threshold must be > 0, got {threshold!r}")
    if period is not None and (
        isinstance(period, bool)
        or not isinstance(period, int | float | np.integer | np.floating)
        or not (math.isfinite(period) and period > 0)
    ):
        raise RecordingError(f"period must be a positive number of seconds, got {period!r}")
    span = float(np.max(s) - np.min(s))
    if span == 0.0:
        raise RecordingError(f"the {kind} signal is constant: no oscillation to analyse")
    sigma = estimate_noise(s) if noise is None else float(noise)
    if not math.isfinite(sigma) or sigma < 0:
        raise RecordingError(f"noise must be a finite number >= 0, got {noise!r}")
    floor = max(threshold * sigma, 1e-4 * span)

    dt = sample_step(t, steps)
    del steps
    if period is None:
        period = dominant_period(t, s)
    per_samples = float(period) / dt
    if per_samples < 6:
        raise RecordingError(
            f"the {kind} signal has {per_samples:.1f} samples per period; at least 6 are "
            "needed to locate extrema"
        )

    # the rest tail after the motion stops (dry friction): flat within the noise
    if rest_band is not None and not (math.isfinite(rest_band) and rest_band > 0):
        raise RecordingError(f"rest_band must be a positive number, got {rest_band!r}")
    band = max(4.0 * sigma if rest_band is None else float(rest_band), 1e-7 * span)
    tail = _rest_tail_start(s, band, math.ceil(per_samples))
    end = s.size if tail is None else tail + 1

    distance = max(1, int(0.6 * per_samples))
    imax, _ = scipy.signal.find_peaks(s[:end], distance=distance, prominence=floor)
    imin, _ = scipy.signal.find_peaks(-s[:end], distance=distance, prominence=floor)
    idx = np.concatenate([imax, imin])
    is_max = np.concatenate([np.ones(imax.size, bool), np.zeros(imin.size, bool)])
    order = np.argsort(idx, kind="stable")
    idx, is_max = _alternate(idx[order], is_max[order], s)

    half_width = max(1, round(per_samples / 12.0))
    tp = np.empty(idx.size)
    vp = np.empty(idx.size)
    for j, i in enumerate(idx.tolist()):
        tp[j], vp[j] = _refine(t, s, i, half_width)

    # a decay without friction fades into the noise: stop at the first small swing
    # after the largest; a small swing before it is a wiggle of the rest before the
    # release (a displacement integrated from a velocity wanders there), not the fade:
    # the extrema up to it are left out
    if vp.size >= 2:
        swings = np.abs(np.diff(vp))
        small = np.flatnonzero(swings < floor)
        before = small[small < int(np.argmax(swings))]
        if before.size:
            first = int(before[-1]) + 1
            tp, vp, idx = tp[first:], vp[first:], idx[first:]
            small = small[small >= first] - first
        if small.size:
            keep = int(small[0]) + 1
            tp, vp, idx = tp[:keep], vp[:keep], idx[:keep]

    tp, vp, idx = tp[skip:], vp[skip:], idx[skip:]
    if tp.size < max(int(min_peaks), 1):
        raise RecordingError(
            f"found {tp.size} usable extrema in the {kind} signal after skipping {skip}; "
            f"at least {min_peaks} are needed"
        )

    rest_raw = None if tail is None else float(np.median(s[tail:]))
    # a parabola over n = 2w+1 samples: variance of its vertex value ≈ (9/4)σ²/n
    value_noise = sigma * math.sqrt(9.0 / 4.0 / (2 * half_width + 1))
    slope = 0.0
    if offset is None:
        c = 0.0
    elif isinstance(offset, str):
        if offset not in ("auto", "constant"):
            raise RecordingError(
                f"offset must be a number, 'auto', 'constant' or None, got {offset!r}"
            )
        if kind == "velocity" and rest_raw is not None:
            c = rest_raw
        elif offset == "auto" and kind == "displacement" and vp.size >= 8:
            c, slope = estimate_offset(vp, tp, drift=True, noise=value_noise)
        elif vp.size >= 4:
            c, _ = estimate_offset(vp, noise=value_noise)
        else:
            c = 0.5 * (float(np.max(vp)) + float(np.min(vp)))
    else:
        c = float(offset)
        if not math.isfinite(c):
            raise RecordingError(f"offset must be finite, got {offset!r}")

    return Peaks(
        t=tp,
        value=vp - c - slope * tp,
        kind=kind,
        offset=c,
        drift=slope,
        noise=sigma,
        index=idx,
        stop_time=None if tail is None else float(t[tail]),
        rest_value=None if rest_raw is None else rest_raw - c - slope * float(t[tail]),
        value_noise=value_noise,
    )
