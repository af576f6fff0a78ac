"""The oscillation frequency of a recording from its zero crossings.

Used where the natural frequency is needed before the energy decay is analysed: a
run whose metadata give the load and the mass but not the frequency takes the
measured one for the stiffness k = m(2πf)² (:meth:`bayestribo.io.run.Run.rig`).

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

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["HYSTERESIS", "crossing_frequency", "oscillation_frequency"]

#: Swing between two counted crossings, as a fraction of the largest excursion.
HYSTERESIS = 0.1


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
    t = np.asarray(time, dtype=np.float64)
    s = np.asarray(values, dtype=np.float64)
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
    if flips.size < 4 or changes.size == 0:
        return None
    # The crossing of a flip is the last sign change before the flip.
    last = changes[np.searchsorted(changes, flips) - 1]
    t0, t1 = t[last], t[last + 1]
    s0, s1 = s[last], s[last + 1]
    # The first crossing after the release is left out: the release (a magnet
    # fading, a hand letting go) takes part of the first half cycle.
    crossing = (t0 + (t1 - t0) * s0 / (s0 - s1))[1:]
    halves = crossing.size - 1
    halves -= halves % 2
    if halves < 4:
        return None
    return float(halves / (2.0 * (crossing[halves] - crossing[0])))


def oscillation_frequency(
    time: ArrayLike, displacement: ArrayLike | None, velocity: ArrayLike | None
) -> float | None:
    """Damped frequency [Hz] of a free decay, from the velocity's zero crossings.

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
        As :func:`crossing_frequency`; None when no two full cycles are found.
    """
    t = np.asarray(time, dtype=np.float64)
    if velocity is not None:
        return crossing_frequency(t, velocity)
    if displacement is None or t.size < 8:
        return None
    x = np.asarray(displacement, dtype=np.float64)
    rough = crossing_frequency(t, x)
    if rough is None:
        return None
    step = float(np.median(np.diff(t)))
    lag = max(1, round(1.0 / (40.0 * rough * step)))
    if 2 * lag >= x.size:
        return None
    derivative = (x[2 * lag :] - x[: -2 * lag]) / (t[2 * lag :] - t[: -2 * lag])
    return crossing_frequency(t[lag:-lag], derivative)
