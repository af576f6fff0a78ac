"""A pendulum recorded as a length: x = r sin θ, and the radius of a simple pendulum.

A video-tracked bob, or a laser or a displacement probe on a pendulum's arm, records
the horizontal position ``x = r sin θ`` of a point at the distance r from the pivot,
not the angle θ. The restoring force of a gravity pendulum is ``sin θ`` in θ, not any
force of x alone, so such a record is fitted as the angle θ = arcsin(x/r)
(:mod:`bayestribo.io.pendulum_arm`). For a simple pendulum (a bob on a light string or
rod) the radius at the bob is its length, ``r = g/ω₀²`` with ω₀ the small swings'
angular frequency; :func:`simple_radius` measures ω₀ from the turning times with the
half periods the pendulum takes at the record's swings (``T(θ_A)/T₀ = 2K(sin²(θ_A/2))/π``,
θ_A = arcsin(A/r)), which depend on r in turn: the two are solved together.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bayestribo.signal.frequency import (
    FrequencyTrend,
    follows,
    trend_beyond,
    turning_point_trend,
)

__all__ = [
    "GRAVITY",
    "arm_advice",
    "arm_half_period_ratio",
    "simple_pendulum_arm",
    "simple_radius",
]

#: The standard acceleration of gravity [m/s²] (local values lie within 0.3 % of it,
#: 9.78 at the equator to 9.83 at the poles): the ``simple`` radius takes it.
GRAVITY = 9.80665


def arm_half_period_ratio(radius: float) -> Callable[[ArrayLike], NDArray]:
    """The pendulum's half period ratio as a function of the recorded swing.

    Parameters
    ----------
    radius : float
        r, the distance from the pivot to the point recorded, in the unit of the swing.

    Returns
    -------
    callable
        ``ratio(A) -> T(θ_A)/T₀`` [-] with θ_A = arcsin(A/r) [rad], A the swing in the
        unit of ``radius``; a ValueError for a swing beyond the radius.
    """
    from bayestribo.model.restoring import get_restoring

    pendulum = get_restoring("pendulum").half_period_ratio

    def ratio(swing: ArrayLike) -> NDArray:
        s = np.abs(np.asarray(swing, dtype=float)) / radius
        if np.any(s >= 1.0):
            raise ValueError("a swing reaches the radius: no angle x = r sin θ gives it")
        return pendulum(np.arcsin(s))

    return ratio


def simple_radius(
    times: ArrayLike, values: ArrayLike, gravity: float = GRAVITY
) -> tuple[float, float] | None:
    """The length of a simple pendulum recorded as ``x = r sin θ``: ``r = g/ω₀²``.

    The turning times are fitted by least squares as ``t_n = t₀ + T₀ S_n``,
    ``S_n = Σ_{m<n} T(θ_m)/T₀`` (θ_m = arcsin(A_m/r), A_m the mean size of two
    neighbouring turning points), and r = g (T₀/π)² with T₀ the small swings' half
    period; starting from the median half period, each pass moves r by the swings'
    share of the period, and the passes stop when r moves by less than 1e-12 of itself.

    Parameters
    ----------
    times : array_like
        Turning times [s], in order, at least 4.
    values : array_like
        The turning points about the equilibrium [m].
    gravity : float
        g [m/s²].

    Returns
    -------
    (float, float) or None
        r [m] and the small swings' frequency ω₀/2π [Hz]; None when the turning times
        give no period, or a swing reaches the radius (the record is no simple
        pendulum's).
    """
    t = np.asarray(times, dtype=float)
    a = np.abs(np.asarray(values, dtype=float))
    if t.size < 4 or t.size != a.size:
        return None
    half = float(np.median(np.diff(t)))
    swing = 0.5 * (a[1:] + a[:-1])
    radius = math.nan
    for _ in range(100):
        if not (math.isfinite(half) and half > 0.0):
            return None
        new = gravity * (half / math.pi) ** 2
        if math.isfinite(radius) and abs(new - radius) <= 1e-12 * radius:
            radius = new
            break
        radius = new
        try:
            ratio = arm_half_period_ratio(radius)(swing)
        except ValueError:
            return None
        steps = np.concatenate(([0.0], np.cumsum(ratio)))
        design = np.column_stack([np.ones_like(steps), steps])
        (_, found), *_ = np.linalg.lstsq(design, t, rcond=None)
        half = float(found)
    else:
        return None
    return radius, 1.0 / (2.0 * half)


def simple_pendulum_arm(
    times: ArrayLike | None, values: ArrayLike, trend: FrequencyTrend | None = None
) -> float | None:
    """The length of a simple pendulum recorded as a length whose half periods follow the
    record's change, if one does.

    A record in metres of a simple pendulum's bob, ``x = r sin θ`` with r = g/ω₀²
    (:func:`~bayestribo.signal.pendulum_arm.simple_radius`), has half periods that
    change with the swing as the pendulum's at θ = arcsin(A/r); they follow the
    measured change when what they leave of it is within its noise or at most
    :data:`~bayestribo.signal.frequency.FOLLOWED` of it (as a force's half periods in
    :func:`~bayestribo.inference.restoring_choice.choose_restoring`).
    That is when ``pendulum_radius_m`` ``"simple"`` (``--pendulum-radius simple``)
    reads the record as the angle it is (:mod:`bayestribo.io.pendulum_arm`).

    Parameters
    ----------
    times : array_like or None
        The turning times [s] (None: none measured).
    values : array_like
        The turning points about the equilibrium [m].
    trend : FrequencyTrend, optional
        The half period's change measured on them (default: measured here).

    Returns
    -------
    float or None
        r [m] when the change is significant and a simple pendulum's follows it; None
        otherwise.
    """
    if times is None:
        return None
    y = np.asarray(values, dtype=float)
    if trend is None:
        trend = turning_point_trend(times, y)
    if trend is None or not math.isfinite(trend.change) or not trend.significant:
        return None
    found = simple_radius(times, y)
    if found is None:
        return None
    radius = found[0]
    return radius if follows(trend_beyond(times, y, arm_half_period_ratio(radius)), trend) else None


def arm_advice(radius: float) -> str:
    """What a warning says to a record in metres that changes as a simple pendulum's
    recorded as a length (:func:`simple_pendulum_arm`) would."""
    return (
        "its half period changes with the swing as a simple pendulum's does when its bob "
        f"is recorded as a length, x = r sin θ with r = g/ω₀² = {radius:.4g} m: no "
        "restoring force of x alone is a pendulum's; pendulum_radius_m='simple' "
        "(--pendulum-radius simple) reads the record as the angle θ = arcsin(x/r) and fits "
        "it with the pendulum's restoring force (for a point at another distance from the "
        "pivot, a laser on the arm, give that distance: --pendulum-radius R); beyond 48° "
        "the angle's noise grows too much for calibrated intervals, which the fit then says"
    )
