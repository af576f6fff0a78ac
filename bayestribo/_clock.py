"""Time stamps: a regular clock, a jittery one, or a gap.

An analysis of a free decay needs samples on a regular clock. Time stamps that
scatter about a regular grid (a scope's or a logger's time column, stamped with a
few microseconds of jitter) are such a clock: each stamp is off by a small, bounded
amount and the grid goes on. A missing sample, a restart of the clock or a resampled
segment is not: the stamps leave the grid by a whole step or more. The two are told
apart by the residuals of the stamps from the best regular grid ``t0 + i h`` (least
squares): jitter keeps every residual within a quarter of a step, a gap puts the
residuals on either side of it a whole step apart (about half a step each).

The samples of a jittered record are taken as the regular grid's
(:func:`bayestribo.signal.decay.check_time` returns it). Where the clock is regular
and the stamps jittered (a time column written by software, or rounded), the grid is
exact; where the samples themselves were taken off the grid, the energy
``E = (y² + y'²)/2`` of a sample read at ``τ + e`` differs from the energy at ``τ`` by
only ``E' e``: E' is the dissipated power, not the oscillation's (the displacement's
error ``y' e`` and the velocity's ``-y e`` cancel in E to first order). On the grid,
±2 µs of jitter on a simulated 10 kHz record of the paper's rig leaves the fit that of
the record without jitter (``tests/test_signal_digitiser.py``). The jitter is recorded
(:attr:`bayestribo.signal.decay.NoiseLevels.timing_jitter_s`).

Dropped samples (a logger that missed a reading, two in a teaching-lab DAQ's minute)
leave the stamps on the grid with whole steps missing: :func:`timeline` finds the
grid and the gaps, and :func:`bridge_gaps` fills each gap of at most
:data:`GAP_LIMIT` of a period with the cubic through its neighbours, where the cubic's
error bound is within the noise; the analysis says which samples it bridged
(:class:`~bayestribo.errors.GapWarning`). A longer gap is refused with the samples
and times, and the advice to fit the parts separately. A clock that restarts (the
stamps fall back and go on) is put on one clock before any of this
(:mod:`bayestribo.signal.restarts`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "GAP_LIMIT",
    "JITTER_LIMIT",
    "Clock",
    "Gap",
    "Timeline",
    "bridge_gaps",
    "clock",
    "on_grid",
    "timeline",
]

#: Largest residual from the regular grid, in steps, that is jitter rather than a gap.
JITTER_LIMIT = 0.25


@dataclass(frozen=True)
class Clock:
    """How regular the time stamps are.

    Attributes
    ----------
    step : float
        The grid's step h [s] (least squares).
    jitter : float
        Standard deviation of the stamps about the grid [s] (0 for a regular clock).
    worst : float
        Largest |residual| in steps.
    first_off : int
        The first sample whose residual is beyond :data:`JITTER_LIMIT` steps (-1 when
        none is: the clock is regular or jittered).
    intercept : float
        The grid's first time t0 [s].
    """

    step: float
    jitter: float
    worst: float
    first_off: int

    intercept: float = 0.0

    def grid(self, n: int) -> np.ndarray:
        """The regular grid ``t0 + i h`` of ``n`` samples [s]."""
        return self.intercept + np.arange(n, dtype=float) * self.step

    @property
    def regular(self) -> bool:
        """True when every stamp is within :data:`JITTER_LIMIT` steps of the grid."""
        return self.first_off < 0


def clock(t: ArrayLike) -> Clock:
    """The regular grid that fits the time stamps, and how far they are from it.

    Parameters
    ----------
    t : array_like
        Strictly increasing time stamps [s] (at least 2).

    Returns
    -------
    Clock

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(1000) * 1e-4
    >>> clock(t + np.random.default_rng(0).uniform(-2e-6, 2e-6, 1000)).regular
    True
    >>> clock(np.delete(t, 500)).regular  # a missing sample
    False
    """
    t = np.asarray(t, dtype=float)
    # least squares: a gap's step then shows as residuals of about half a step on
    # either side of it, beyond the jitter limit
    return _fitted_grid(np.arange(t.size, dtype=float), t)


def _fitted_grid(index: np.ndarray, t: np.ndarray) -> Clock:
    """The grid ``t0 + i h`` fitted by least squares to stamps ``t`` at grid indices
    ``index``, and the stamps' residuals from it."""
    slope, intercept = np.polyfit(index, t, 1)
    h = float(slope)
    residual = t - (intercept + index * h)
    off = np.flatnonzero(np.abs(residual) > JITTER_LIMIT * h)
    return Clock(
        step=h,
        jitter=float(np.std(residual)),
        worst=float(np.max(np.abs(residual)) / h),
        first_off=int(off[0]) if off.size else -1,
        intercept=float(intercept),
    )


#: Longest gap bridged, as a fraction of the oscillation period: a cubic through two
#: samples on each side of a gap of a tenth of a period is off by at most 4e-4 of the
#: swing (:func:`bridge_gaps`); a longer one splits the cycle it falls in.
GAP_LIMIT = 0.1


@dataclass(frozen=True)
class Gap:
    """Samples missing from a regular clock.

    Attributes
    ----------
    after : int
        The sample (counting from 0 in the record as given) after which they are missing.
    missing : int
        How many grid steps hold no sample.
    time : float
        The time stamp of sample ``after`` [s].
    error_bound : float
        Largest error of the bridged samples, in the signal's unit (0 before bridging).
    """

    after: int
    missing: int
    time: float
    error_bound: float = 0.0

    def describe(self, unit: str = "") -> str:
        """One phrase: where, how many, and the bridge's error bound."""
        text = f"{self.missing} sample(s) after sample {self.after} (t = {self.time:.6g} s)"
        if self.error_bound > 0:
            text += f", bridged within ±{self.error_bound:.2g}{unit}"
        return text


@dataclass(frozen=True)
class Timeline:
    """Time stamps on a regular grid with samples missing.

    Attributes
    ----------
    clock : Clock
        The grid fitted to the stamps by their grid indices, and the jitter about it.
    index : ndarray of int
        Each stamp's index on the grid (increasing, not always by one).
    gaps : tuple of Gap
        Where the index jumps by more than one.
    """

    clock: Clock
    index: np.ndarray
    gaps: tuple[Gap, ...]

    @property
    def on_grid(self) -> bool:
        """True when every stamp is within :data:`JITTER_LIMIT` steps of its grid time."""
        return self.clock.regular


def timeline(t: ArrayLike) -> Timeline:
    """The regular grid that strictly increasing time stamps sit on, with their gaps.

    Each step between stamps is a whole number of grid steps (the median step's
    multiple nearest to it); the grid is then fitted by least squares to the stamps
    against their grid indices, so the jitter and the gaps are told apart: a stamp off
    its grid time by more than :data:`JITTER_LIMIT` steps (a restarted or resampled
    clock, a step of 1.5 grid steps) leaves ``on_grid`` False.

    Parameters
    ----------
    t : array_like
        Strictly increasing time stamps [s] (at least 2).

    Returns
    -------
    Timeline

    Examples
    --------
    >>> import numpy as np
    >>> t = np.delete(np.arange(1000) * 1e-2, [400, 700, 701])
    >>> [(g.after, g.missing) for g in timeline(t).gaps]
    [(399, 1), (698, 2)]
    """
    t = np.asarray(t, dtype=float)
    dt = np.diff(t)
    h0 = float(np.median(dt))
    steps = np.maximum(np.rint(dt / h0), 1.0)
    index = np.concatenate([[0], np.cumsum(steps)]).astype(np.int64)
    fitted = _fitted_grid(index.astype(float), t)
    jumps = np.flatnonzero(steps > 1)
    gaps = tuple(Gap(int(i), int(steps[i]) - 1, float(t[i])) for i in jumps)
    return Timeline(fitted, index, gaps)


def _noise_sd(values: np.ndarray) -> float:
    """Robust standard deviation of white noise on a smooth signal: the median absolute
    fourth difference (variance 70 σ² for white noise)."""
    d4 = np.diff(values, 4)
    return float(1.4826 * np.median(np.abs(d4)) / math.sqrt(70.0)) if d4.size else 0.0


def bridge_gaps(
    t: ArrayLike,
    signals: dict[str, np.ndarray | None],
    period: float,
    *,
    limit: float = GAP_LIMIT,
) -> tuple[np.ndarray, dict[str, np.ndarray | None], tuple[Gap, ...]]:
    """Put a record with missing samples on its regular grid, bridging each gap.

    Each missing sample is the cubic through the two samples on each side of its gap
    (Lagrange, at their grid times). For a motion of swing A and circular frequency ω
    its error is at most ``A ω⁴ h⁴ |Π(k - k_i)| / 24`` (the cubic's remainder, with
    ``|x''''| <= A ω⁴``), which the gap reports; a gap is bridged only when it spans at
    most ``limit`` of a period and that bound is within the noise of the signal (its
    robust sd from fourth differences, or one quantisation step).

    Parameters
    ----------
    t : array_like
        Strictly increasing time stamps [s] on a grid with gaps (:func:`timeline`).
    signals : dict of str to ndarray or None
        The recorded channels by name, one value per stamp.
    period : float
        The oscillation period [s].
    limit : float
        Longest gap bridged, as a fraction of the period.

    Returns
    -------
    t : ndarray
        The regular grid [s].
    signals : dict
        Each channel on the grid, the recorded samples unchanged.
    gaps : tuple of Gap
        The gaps, with their error bounds.

    Raises
    ------
    RecordingError
        Naming the samples and the times: stamps off the grid (a restarted or resampled
        clock), a gap longer than ``limit`` of a period, a gap at which the bridge's
        error bound exceeds the noise, or one within two samples of the record's end.
    """
    from bayestribo.errors import RecordingError

    t = np.asarray(t, dtype=float)
    line = timeline(t)
    h = line.clock.step
    if not line.on_grid:
        i = line.clock.first_off
        raise RecordingError(
            f"time stamps leave the regular grid at sample {i} (t = {t[i]:.6g} s) by "
            f"{line.clock.worst:.2g} steps of {h:.6g} s, not a whole number of samples: a "
            "restarted or resampled clock; crop the record to one clock (--window T0:T1)"
        )
    n = int(line.index[-1]) + 1
    out: dict[str, np.ndarray | None] = {}
    bounds = {g.after: 0.0 for g in line.gaps}
    for name, values in signals.items():
        if values is None:
            out[name] = None
            continue
        values = np.asarray(values, dtype=float)
        grid = np.full(n, np.nan)
        grid[line.index] = values
        swing = float(np.max(np.abs(values - np.median(values))))
        omega = 2.0 * math.pi / period
        steps = np.abs(np.diff(np.unique(values)))
        quantum = float(steps.min()) if steps.size else 0.0
        floor = max(_noise_sd(values), quantum)
        for gap in line.gaps:
            i = gap.after
            if gap.missing * h > limit * period:
                raise RecordingError(
                    f"field {name!r}: {gap.missing} samples are missing after sample {i} "
                    f"(t = {t[i]:.6g} s to {t[i + 1]:.6g} s), {gap.missing * h / period:.2g} of a "
                    f"period; a gap longer than {limit:g} of a period cannot be bridged: "
                    "fit the parts on either side separately (--window T0:T1)"
                )
            if i < 1 or i + 2 >= t.size:
                raise RecordingError(
                    f"field {name!r}: samples are missing after sample {i} (t = {t[i]:.6g} s), "
                    "within two samples of the record's end; crop it (--window T0:T1)"
                )
            k = line.index[[i - 1, i, i + 1, i + 2]].astype(float)
            y = values[[i - 1, i, i + 1, i + 2]]
            missing = np.arange(line.index[i] + 1, line.index[i + 1]).astype(float)
            filled = np.zeros(missing.size)
            product = np.ones(missing.size)
            for a in range(4):
                others = [b for b in range(4) if b != a]
                basis = np.prod([(missing - k[b]) / (k[a] - k[b]) for b in others], axis=0)
                filled += y[a] * basis
                product *= missing - k[a]
            bound = swing * (omega * h) ** 4 * float(np.max(np.abs(product))) / 24.0
            if bound > floor:
                raise RecordingError(
                    f"field {name!r}: {gap.missing} sample(s) are missing after sample {i} "
                    f"(t = {t[i]:.6g} s); bridging them could be off by {bound:.2g}, beyond the "
                    f"noise {floor:.2g}: fit the parts on either side separately "
                    "(--window T0:T1)"
                )
            grid[missing.astype(np.int64)] = filled
            bounds[i] = max(bounds[i], bound)
        out[name] = grid
    gaps = tuple(Gap(g.after, g.missing, g.time, bounds[g.after]) for g in line.gaps)
    return line.clock.grid(n), out, gaps


def on_grid(
    t: ArrayLike, displacement: ArrayLike | None, velocity: ArrayLike | None
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None, tuple[Gap, ...]]:
    """A record with missing samples put on its regular grid (:func:`bridge_gaps`).

    Parameters
    ----------
    t : array_like
        Time stamps [s].
    displacement, velocity : array_like or None
        The recorded channels.

    Returns
    -------
    t, displacement, velocity : ndarray
        Unchanged where no sample is missing (or the stamps are not strictly increasing
        and finite: the checks that follow name that); else on the regular grid.
    gaps : tuple of Gap
        The bridged gaps (empty when none).

    Raises
    ------
    RecordingError
        As :func:`bridge_gaps`, and when no oscillation period can be measured to judge
        the gaps by.
    """
    from bayestribo.errors import RecordingError
    from bayestribo.signal.frequency import oscillation_frequency

    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size < 16 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        return t, displacement, velocity, ()
    line = timeline(t)
    if not line.gaps:
        return t, displacement, velocity, ()
    x = None if displacement is None else np.asarray(displacement, dtype=float)
    v = None if velocity is None else np.asarray(velocity, dtype=float)
    if (x is not None and x.shape != t.shape) or (v is not None and v.shape != t.shape):
        return t, displacement, velocity, ()  # the checks that follow name the shapes
    frequency = oscillation_frequency(t, x, v)
    if frequency is None or not frequency > 0:
        first = line.gaps[0]
        raise RecordingError(
            f"time stamps: {first.describe()} and no oscillation period was found to judge "
            "whether the gap can be bridged"
        )
    grid, bridged, gaps = bridge_gaps(t, {"displacement": x, "velocity": v}, 1.0 / frequency)
    return grid, bridged["displacement"], bridged["velocity"], gaps
