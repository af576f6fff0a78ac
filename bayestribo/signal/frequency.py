"""The oscillation frequency of a recording from its zero crossings.

Used where the natural frequency is needed before the energy decay is analysed: a
run whose metadata give the load and the mass but not the frequency takes the
measured one for the stiffness k = m(2πf)² (:meth:`bayestribo.io.run.Run.rig`), and
where the fit asks whether the frequency changes with the amplitude
(:func:`frequency_trend`, :func:`turning_point_trend`).

The frequency is taken from the zero crossings of the velocity (the turning points
of the displacement): with viscous damping and Coulomb friction these are exactly
half a damped period apart, while the displacement's own zero crossings drift as the
Coulomb offset ±x_c grows against the decaying amplitude. Crossings are counted
with hysteresis (the signal must swing beyond ±10 % of its
largest excursion between two crossings), so noise at rest adds none. Coulomb
friction shifts the centre of each half cycle by ±x_c, alternately, which moves
single crossings but not a pair: the frequency is taken over an even number of half
cycles. It is the damped frequency Ω√(1-ζ²), 0.03 % below the natural frequency at
ζ = 0.024; Coulomb friction leaves the period unchanged.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.errors import RecordingError
from bayestribo.signal.period import dominant_period, sample_step

__all__ = [
    "FOLLOWED",
    "FREQUENCY_TREND_CHANGE",
    "FREQUENCY_TREND_Z",
    "HYSTERESIS",
    "FrequencyTrend",
    "crossing_frequency",
    "follows",
    "frequency_trend",
    "oscillation_frequency",
    "trend_beyond",
    "turning_point_trend",
]

#: A half period changing along the decay by more than this fraction, and by more than
#: FREQUENCY_TREND_Z standard errors, is beyond its noise (:attr:`FrequencyTrend.
#: significant`): the linear law's Ω is constant.
FREQUENCY_TREND_CHANGE = 2e-4

FREQUENCY_TREND_Z = 4.0

#: Swing between two counted crossings, as a fraction of the largest excursion.
HYSTERESIS = 0.1


def _crossings(t: NDArray, s: NDArray) -> tuple[NDArray, NDArray] | None:
    """Zero crossings of ``s`` (median removed) with hysteresis: their interpolated
    times [s] and the sample index before each; None without an oscillation."""
    s = s - np.median(s)
    peak = float(np.max(np.abs(s))) if s.size else 0.0
    if not np.isfinite(peak) or peak == 0.0:
        return None
    level = HYSTERESIS * peak
    state = np.where(s > level, 1, np.where(s < -level, -1, 0))
    beyond = np.flatnonzero(state)
    if beyond.size < 2:
        return None
    states = state[beyond]
    # Indices where the filled state flips: a half cycle is complete there.
    flips = beyond[1:][states[1:] != states[:-1]]
    positive = s > 0
    changes = np.flatnonzero(positive[1:] != positive[:-1])
    if flips.size == 0 or changes.size == 0:
        return None
    # The crossing of a flip is the last sign change before the flip.
    last = changes[np.searchsorted(changes, flips) - 1]
    t0, t1 = t[last], t[last + 1]
    s0, s1 = s[last], s[last + 1]
    return t0 + (t1 - t0) * s0 / (s0 - s1), last


def crossing_frequency(time: ArrayLike, values: ArrayLike) -> float | None:
    """Frequency [Hz] of an oscillation from its zero crossings.

    Parameters
    ----------
    time : array_like
        Sample times [s], increasing.
    values : array_like
        Displacement or velocity samples (any unit); the median is taken as zero.

    Returns
    -------
    float or None
        The mean frequency over an even number of half cycles after the first
        crossing, or None when fewer than two full cycles swing beyond the
        hysteresis.
    """
    found = _crossings(np.asarray(time, dtype=np.float64), np.asarray(values, dtype=np.float64))
    if found is None:
        return None
    # The first crossing after the release is left out: the release (a magnet
    # fading, a hand letting go) takes part of the first half cycle.
    crossing = found[0][1:]
    halves = crossing.size - 1
    halves -= halves % 2
    if halves < 4:
        return None
    return float(halves / (2.0 * (crossing[halves] - crossing[0])))


#: How far above the spectrum's frequency the zero crossings' may be before
#: :func:`oscillation_frequency` takes them to count more than the oscillation's
#: (spurious crossings only add; the spectrum's peak on a record of a few cycles is
#: within about a sixth of the frequency, so a crossings' frequency that is right is
#: never this far above it).
CROSSING_SPECTRUM_TOLERANCE = 0.25


def oscillation_frequency(
    time: ArrayLike, displacement: ArrayLike | None, velocity: ArrayLike | None
) -> float | None:
    """Damped frequency [Hz] of a free decay, from the velocity's zero crossings,
    checked against the spectrum.

    Crossings that are not the oscillation's add to the count and raise the frequency:
    where the oscillation has decayed into the noise, or a higher mode of the rig (a
    beam's second bending mode, 6.3 times the first) swings the velocity through zero
    between its turning points. Where the crossings' frequency is more than
    :data:`CROSSING_SPECTRUM_TOLERANCE` above the spectrum's
    (:func:`~bayestribo.signal.period.dominant_period` of the displacement, or of the
    velocity without one), the spectrum's is returned (a beam with a second mode at 3 %
    of the release: 48.6 Hz by the crossings for 32.6 Hz; a displacement alone with 1.5 %
    of the release in white noise: 120.9 Hz; ``tests/test_signal_frequency_spurious.py``).

    Parameters
    ----------
    time : array_like
        Sample times [s], regularly spaced.
    displacement, velocity : array_like or None
        The signals; the velocity is used when given, else a central difference of
        the displacement over about a fortieth of a period (symmetric, so it shifts
        no crossing).

    Returns
    -------
    float or None
        As :func:`crossing_frequency`, or the spectrum's where they disagree; None when
        no two full cycles are found.
    """
    t = np.asarray(time, dtype=np.float64)
    if velocity is not None:
        found = crossing_frequency(t, velocity)
    elif displacement is None or t.size < 8:
        return None
    else:
        derived = _central_difference(t, np.asarray(displacement, dtype=np.float64))
        found = None if derived is None else crossing_frequency(derived[0], derived[1])
    if found is None:
        return None
    signal = displacement if displacement is not None else velocity
    try:
        spectral = 1.0 / dominant_period(t, np.asarray(signal, dtype=np.float64))
    except RecordingError:
        return found
    if found > (1.0 + CROSSING_SPECTRUM_TOLERANCE) * spectral:
        return float(spectral)
    return found


def _central_difference(t: NDArray, x: NDArray) -> tuple[NDArray, NDArray, NDArray] | None:
    """(times, dx/dt, x at those times): a central difference of the displacement over
    about a fortieth of its period (:func:`~bayestribo.signal.period.dominant_period`;
    symmetric, so it shifts no crossing); None without an oscillation."""
    try:
        period = dominant_period(t, x)
    except RecordingError:
        return None
    step = sample_step(t)
    lag = max(1, round(period / (40.0 * step)))
    if 2 * lag >= x.size:
        return None
    derivative = (x[2 * lag :] - x[: -2 * lag]) / (t[2 * lag :] - t[: -2 * lag])
    return t[lag:-lag], derivative, x[lag:-lag]


@dataclass(frozen=True)
class FrequencyTrend:
    """How the half period of the oscillation changes with its amplitude.

    Attributes
    ----------
    change : float
        Relative change of the half period over the amplitude span of the decay,
        from the largest to the smallest swing [-]; 0 for a linear oscillator
        (viscous damping and Coulomb friction leave the period unchanged).
    z : float
        ``change`` over its standard error (residual scatter of the turning times).
    n_half_cycles : int
        Half cycles used.
    """

    change: float
    z: float
    n_half_cycles: int

    def to_dict(self) -> dict[str, float | int]:
        """JSON-ready values."""
        return {"change": self.change, "z": self.z, "n_half_cycles": self.n_half_cycles}

    @property
    def significant(self) -> bool:
        """True when the change is beyond its noise: more than
        :data:`FREQUENCY_TREND_CHANGE` and more than :data:`FREQUENCY_TREND_Z` standard
        errors."""
        return abs(self.change) > FREQUENCY_TREND_CHANGE and abs(self.z) > FREQUENCY_TREND_Z


def frequency_trend(
    time: ArrayLike, displacement: ArrayLike | None, velocity: ArrayLike | None
) -> FrequencyTrend | None:
    """Half periods against amplitude: is the oscillator's frequency constant?

    The turning points are the velocity's zero crossings (exactly half a damped period
    apart for viscous damping and Coulomb friction, Eq. 15), straight-line
    interpolated; each half period is set against its swing, half the distance
    between its two turning points (:func:`turning_point_trend`). The fit uses the
    energy decay's turning times instead, each side's damped arc solved in closed
    form (:attr:`bayestribo.signal.decay.EnergyDecay.turning_times`). A stiffness
    that depends on amplitude (a cubic spring, a contact stiffness) makes the half
    period change along the decay, which the linear law's constant Ω cannot follow:
    the fit then biases ζ (a frequency change of 0.06 % over the decay moves ζ by
    about two posterior standard deviations at ten times the resolution).

    Parameters
    ----------
    time : array_like
        Regular sample times [s].
    displacement, velocity : array_like or None
        The signals; without a velocity, a central difference of the displacement.

    Returns
    -------
    FrequencyTrend or None
        None without a displacement or with fewer than 6 half cycles.
    """
    t = np.asarray(time, dtype=np.float64)
    if displacement is None or t.size < 8:
        return None
    x = np.asarray(displacement, dtype=np.float64)
    if velocity is not None:
        v, tv, xv = np.asarray(velocity, dtype=np.float64), t, x
    else:
        derived = _central_difference(t, x)
        if derived is None:
            return None
        tv, v, xv = derived
    found = _crossings(tv, v)
    if found is None:
        return None
    times, index = found[0][1:], found[1][1:]  # the release's half cycle left out
    turning = xv[index]
    # the equilibrium: the mean of consecutive turning points' midpoints (Coulomb
    # friction moves them by ±x_c, alternately)
    return turning_point_trend(times, turning - np.mean(0.5 * (turning[1:] + turning[:-1])))


#: Turning points needed for a trend: five coefficients and three degrees of freedom.
MIN_TREND_TURNING_POINTS = 8


def turning_point_trend(times: ArrayLike, values: ArrayLike) -> FrequencyTrend | None:
    """Frequency trend from turning times and the turning points' values.

    The turning times are fitted by weighted least squares as

        t_n = t_0 + n T + s Σ_{m<n} (A_m - Ā) + b₁/|Y_n| + b₂/|Y_n|²,

    T the half period, A_m = ½|Y_{m+1} - Y_m| the swing of half cycle m (Ā their
    mean), so that each half period is T + s(A_n - Ā) plus the change of the b terms:
    s is the trend of the half period with the swing. The b terms absorb what moves a
    measured turning time by an amount that grows as the amplitude decays: an
    anti-alias filter smooths the kink Coulomb friction puts in the velocity at each
    turning point, which moves the filtered velocity's zero by about x_c/|Y_n| times
    the filter's spread in time (first order; the slopes Ω²(|Y_n| ± x_c) on either
    side give the second), and a straight line between the two samples around the
    zero is late by about h a(1-a) 2x_c/|Y_n| (h the sample spacing, a the crossing's
    fraction of the way between them). Without them a linear oscillator's record
    through a 4th-order 2 kHz Butterworth filter showed a trend of -1.2e-5 at
    z = -1.6 (10 kHz) and -7e-6 at z = -6.7 (100 kHz). Fitting the turning times
    (independent errors, weighted by |Y_n|, the inverse of their noise) rather than
    the half periods (neighbours share a time) gives the slope's standard error from
    the residual scatter.

    Parameters
    ----------
    times : array_like
        Turning times [s], in order (e.g.
        :attr:`bayestribo.signal.decay.EnergyDecay.turning_times`).
    values : array_like
        The displacement at each turning point about the equilibrium (any unit),
        alternating in sign.

    Returns
    -------
    FrequencyTrend or None
        None with fewer than 8 turning points, a zero value, or a singular design.
    """
    tt = np.asarray(times, dtype=np.float64)
    y = np.asarray(values, dtype=np.float64)
    if tt.size != y.size:
        raise ValueError(f"times and values differ in length ({tt.size}, {y.size})")
    if tt.size < MIN_TREND_TURNING_POINTS or not np.all(np.isfinite(tt) & np.isfinite(y)):
        return None
    w = np.abs(y)
    if np.any(w == 0.0):
        return None
    swing = 0.5 * np.abs(np.diff(y))
    n = np.arange(tt.size, dtype=np.float64)
    trend = np.concatenate(([0.0], np.cumsum(swing - swing.mean())))
    design = np.column_stack((np.ones_like(n), n, trend, 1.0 / w, 1.0 / (w * w)))
    # columns scaled to unit norm: 1/|Y|² spans many decades
    weighted = design * w[:, None]
    norm = np.linalg.norm(weighted, axis=0)
    if np.any(norm == 0.0):
        return None
    scaled = weighted / norm
    coef, _, rank, _ = np.linalg.lstsq(scaled, tt * w, rcond=None)
    if rank < design.shape[1]:
        return None
    residual = tt * w - scaled @ coef
    dof = tt.size - design.shape[1]
    s2 = float(residual @ residual) / dof
    cov = s2 * np.linalg.inv(scaled.T @ scaled)
    coef, se = coef / norm, float(np.sqrt(cov[2, 2])) / norm[2]
    span = float(swing.max() - swing.min())
    # The half period is T + s(A - Ā): from the largest swing to the smallest it
    # changes by -s·span (a hardening spring, s < 0, gives a positive change).
    change = float(-coef[2] / coef[1] * span)
    if se > 0:
        z = float(-coef[2] / se)
    else:
        z = 0.0 if coef[2] == 0 else math.copysign(math.inf, change)
    return FrequencyTrend(change, z, int(swing.size))


#: The largest share of the measured change a force's half periods may leave and still
#: be said to follow it (rules 2 and 3 of
#: :mod:`bayestribo.inference.restoring_choice`'s notes) [-].
FOLLOWED = 0.1


def follows(left: FrequencyTrend | None, trend: FrequencyTrend) -> bool:
    """True when a force leaves of the measured change ``trend`` at most what its noise
    or :data:`FOLLOWED` of it allows (``left``: what the force leaves; None: nothing
    measured)."""
    return left is not None and (
        not left.significant or abs(left.change) <= FOLLOWED * abs(trend.change)
    )


def trend_beyond(
    times: ArrayLike, values: ArrayLike, ratio: Callable[[ArrayLike], NDArray]
) -> FrequencyTrend | None:
    """The half period's change beyond a restoring force's own.

    The force's half periods at the record's swings, ``T₀ T(A_m)/T₀`` (A_m the mean of
    two turning points' sizes, T₀ and t₀ fitted to the turning times by least squares),
    make the turning times uneven; that unevenness is taken off the record's turning
    times and the change measured again (:func:`~bayestribo.signal.frequency.
    turning_point_trend`), its standard error the record's own.

    Parameters
    ----------
    times : array_like
        Turning times [s], in order.
    values : array_like
        The turning points about the equilibrium, in the unit the force takes.
    ratio : callable
        The force's ``half_period_ratio`` [-].

    Returns
    -------
    FrequencyTrend or None
        None with too few turning points or a force that has no half period at these
        swings (a pendulum at π, a softening spring past its turning-over point).
    """
    t = np.asarray(times, dtype=float)
    y = np.asarray(values, dtype=float)
    a = np.abs(y)
    try:
        steps = np.concatenate(([0.0], np.cumsum(ratio(0.5 * (a[1:] + a[:-1])))))
    except ValueError:
        return None
    if not np.all(np.isfinite(steps)):
        return None
    n = np.arange(steps.size, dtype=float)
    design = np.column_stack([np.ones_like(steps), steps])
    (_, half), *_ = np.linalg.lstsq(design, t, rcond=None)
    uneven = steps - np.polyval(np.polyfit(n, steps, 1), n)
    return turning_point_trend(t - float(half) * uneven, y)
