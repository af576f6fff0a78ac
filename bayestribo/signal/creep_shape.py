"""A creep seen on one recorded channel: its path towards the equilibrium.

With both channels recorded, a creep after the stop is told from a sensor's drift by
the two channels moving as one (:mod:`bayestribo.signal.creep`). With one channel (a
displacement alone, the velocity derived from it; or a velocity alone, the
displacement integrated from it) nothing agrees or disagrees, and what moves a rest
may be the sensor: an offset that drifts (linearly, or as a 1/f wander), mains hum, a
digitiser's steps. The creep is then told by where it goes and how:

* **towards the equilibrium.** The mass creeps towards the equilibrium the oscillation
  was centred on (the turning points' equilibrium at the last turning point, held over
  the rest: its fitted drift is a law's misfit as often as a sensor's, and is not
  extended), and does not pass it. A drift does not know where the equilibrium is. A
  velocity alone is integrated with its median at rest taken as its offset (a creep's
  own pace there), so its equilibrium's line is extended and a line fitted beside the
  approach is taken off, which may move the rest by at most :data:`SLOPE_SHARE` of the
  approach's move; a velocity whose offset drifts between its two rests is not tested
  (its :class:`~bayestribo.errors.OffsetDriftWarning` already says the rest moved);
* **decelerating.** The spring's force, which drives the creep, shrinks as the mass
  approaches: the move over the rest's first third exceeds the move over its last
  third by :data:`DECELERATION` or more, and an exponential approach to the
  equilibrium (one time constant, its level fixed there) follows the rest's block
  means within :data:`SHAPE_TOLERANCE` of the move, and within :data:`CURVATURE` of
  what a straight line (a drift's steady pace) leaves: a creep slow enough to look
  straight over the rest is not told from a drift. A 1/f wander or hum moves the
  block means about any smooth path by more than that;
* **continuous with the motion.** The approach, extended back to the stop, starts
  inside the last turning point's swing, at a pace below the last half cycle's peak
  speed;
* **absent before the release.** A rest recorded before the release, where the mass
  is held, moves (relative to the equilibrium's line) at no comparable pace: an offset
  drift would move it too.

The move over the rest (first third's mean to last third's) must exceed
:data:`~bayestribo.signal.creep.CREEP_Z` standard errors of the recorded channel's
white noise (for a velocity alone, of its integral) and two digitiser steps.

Measured (``benchmarks/creep_one_channel.py``, ``results/creep_one_channel.json``):
no false alarm on the 63 bundled runs with either channel alone, the real recordings
of ``../shared/external-data``, or 720 simulated one-channel records with an offset
drifting linearly or as a random walk, 1/f noise, hum or digitiser steps; of 58
simulated Stribeck records that creep beyond the noise, 58 found with the displacement
alone and 42 with the velocity alone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "BLOCKS",
    "CURVATURE",
    "DECELERATION",
    "SHAPE_TOLERANCE",
    "RestPath",
    "ShapeCreep",
    "creep_towards_equilibrium",
    "rest_path",
]

#: Standard errors of white noise the move over the rest must exceed (as the two
#: channels' test, :data:`bayestribo.signal.creep.CREEP_Z`).
MOVE_Z = 8.0
#: Block means the rest's path is followed by.
BLOCKS = 24
#: Fewest samples per block.
MIN_BLOCK_SAMPLES = 4
#: Least ratio of the first third's move to the last third's.
DECELERATION = 1.2
#: Largest rms of the block means about the exponential approach, as a fraction of the
#: move.
SHAPE_TOLERANCE = 0.1
#: Largest ratio of the rms about the exponential approach to the rms about a straight
#: line: the approach must be curved beyond what a drift's steady pace explains.
CURVATURE = 0.5
#: Largest share of the move by which a block mean may lie beyond the equilibrium.
OVERSHOOT = 0.1
#: Largest share of the move a rest before the release may make over as long a time.
BEFORE_SHARE = 0.25
#: Largest move of the line fitted beside the approach (a velocity alone), as a share
#: of the approach's own move: the creep, not the equilibrium's unknown pace, moves it.
SLOPE_SHARE = 1.0
#: Standard errors by which the rest before the release must move to be a drift.
HELD_Z = 4.0
#: Time constants tried, as multiples of the rest's length.
_TAUS = np.geomspace(0.02, 50.0, 121)


@dataclass(frozen=True)
class ShapeCreep:
    """A rest after the stop that creeps towards the equilibrium, seen on one channel.

    Attributes
    ----------
    channel : {"displacement", "velocity"}
        The channel recorded (the other is derived from it).
    start, end : float
        The rest tested [s].
    distance : float
        Its first third's distance from the equilibrium [length unit].
    move : float
        How far it moves towards the equilibrium, first third to last [length unit].
    move_z : float
        That move in standard errors of the recorded channel's white noise.
    time_constant : float
        The exponential approach's time constant [s].
    deceleration : float
        The first third's move over the last third's.
    """

    channel: str
    start: float
    end: float
    distance: float
    move: float
    move_z: float
    time_constant: float
    deceleration: float

    def describe(self) -> str:
        """One sentence for the warning."""
        other = "velocity" if self.channel == "displacement" else "displacement"
        return (
            f"the {self.channel} is recorded alone (the {other} derived from it); from "
            f"t = {self.start:.6g} s to {self.end:.6g} s the mass moves {self.move:.3g} "
            f"({self.move_z:.0f} standard errors of the noise) of the {self.distance:.3g} "
            "between it and the equilibrium its oscillation was centred on, towards it "
            f"and slowing down (an exponential approach, time constant "
            f"{self.time_constant:.3g} s; the first third's move {self.deceleration:.2g} "
            "times the last's), where a drift of the sensor's offset would not know to go: "
            "the mass creeps on after its last half cycle"
        )


def _move_se(recorded: str, sigma: float, dt: float, n: int) -> float:
    """Standard error of the difference of the first and last thirds' means of ``n``
    samples of white noise of sd ``sigma`` (recorded displacement) or of its integral
    with sample step ``dt`` [s] (recorded velocity)."""
    if recorded == "velocity":
        return sigma * dt * math.sqrt(2.0 * n / 3.0)
    return sigma * math.sqrt(6.0 / n)


def _thirds(r: NDArray) -> tuple[float, float, float]:
    parts = np.array_split(r, 3)
    return float(np.mean(parts[0])), float(np.mean(parts[1])), float(np.mean(parts[2]))


def _approach(
    c: NDArray, m: NDArray, length: float, slope: bool
) -> tuple[float, float, float, float]:
    """The exponential approach to zero A exp(-c/τ) (plus a line b c through zero when
    ``slope``) closest to the block means ``m`` at times ``c`` (from the rest's start)
    [s]: (A, τ, rms of the residuals, b)."""
    taus = _TAUS * length
    e = np.exp(-np.outer(1.0 / taus, c))  # one row per time constant
    ee, em = np.einsum("ij,ij->i", e, e), e @ m
    if slope:
        # the 2x2 normal equations of (A, b) on the basis (e, c), for every τ at once
        ec, cc, cm = e @ c, float(c @ c), float(c @ m)
        det = ee * cc - ec * ec
        a = (em * cc - ec * cm) / det
        b = (ee * cm - ec * em) / det
    else:
        a, b = em / ee, np.zeros(taus.size)
    residual = m - a[:, None] * e - b[:, None] * c
    rms = np.sqrt(np.mean(residual * residual, axis=1))
    k = int(np.argmin(rms))
    return float(a[k]), float(taus[k]), float(rms[k]), float(b[k])


def _line_rms(c: NDArray, m: NDArray) -> float:
    coef = np.polyfit(c, m, 1)
    return float(np.sqrt(np.mean((m - np.polyval(coef, c)) ** 2)))


@dataclass(frozen=True)
class RestPath:
    """What the rest after the stop does, measured against the equilibrium (the
    quantities :func:`creep_towards_equilibrium` tests; NaN where not measured).

    Attributes
    ----------
    start, end : float
        The rest [s].
    distance : float
        Its first third's distance from the equilibrium [length unit].
    move : float
        Its move towards the equilibrium, first third's mean to last third's [length
        unit] (negative: away from it).
    move_z : float
        That move in standard errors of the recorded channel's white noise.
    move_floor : float
        Two digitiser steps of the move [length unit] (0 when not quantised).
    deceleration : float
        The first third's move towards the equilibrium over the last third's (inf when
        the last third's is not towards it).
    early : float
        The first third's move towards the equilibrium [length unit].
    overshoot : float
        The farthest block mean beyond the equilibrium, over the move.
    shape : float
        The rms of the block means about the exponential approach, over the move.
    line : float
        The rms of the block means about a straight line, over the move.
    time_constant : float
        The approach's time constant [s].
    at_stop : float
        The approach extended back to the stop, over the last turning point's swing.
    pace : float
        Its pace there, over the last half cycle's peak speed (ω times that swing).
    held : float
        The rest before the release's move over as long a time as the rest after the
        stop, over the move (0 when it does not move beyond :data:`HELD_Z` standard
        errors, NaN when there is no rest before the release).
    slope_share : float
        How far the line fitted beside the approach (a velocity alone) moves over the
        rest, over the move (0 when none is fitted).
    """

    start: float
    end: float
    distance: float
    move: float
    move_z: float
    move_floor: float
    deceleration: float
    early: float
    overshoot: float
    shape: float
    line: float
    time_constant: float
    at_stop: float
    pace: float
    held: float
    slope_share: float = 0.0

    def creeps(self) -> bool:
        """Every condition of the module notes holds."""
        return bool(
            self.move_z > MOVE_Z
            and self.move > self.move_floor
            and self.early > 0
            and self.deceleration >= DECELERATION
            and self.overshoot <= OVERSHOOT
            and self.shape <= SHAPE_TOLERANCE
            and self.shape <= CURVATURE * self.line
            and self.at_stop <= 1.0
            and self.pace <= 1.0
            and not self.held >= BEFORE_SHARE
            and self.slope_share <= SLOPE_SHARE
        )


def rest_path(
    t: NDArray,
    y: NDArray,
    equilibrium: NDArray,
    start: int,
    *,
    recorded: str,
    sigma: float,
    stop_time: float,
    last_swing: float,
    omega: float,
    before: int = 0,
    step: float | None = None,
    free_slope: bool = False,
) -> RestPath | None:
    """What the rest ``t[start:]`` of a record with one channel does (the parameters of
    :func:`creep_towards_equilibrium`); None when it is too short to say (fewer than 6
    blocks of :data:`MIN_BLOCK_SAMPLES`) or the noise is not measured."""
    n = t.size - start
    blocks = min(BLOCKS, n // MIN_BLOCK_SAMPLES)
    if blocks < 6 or not sigma > 0 or not last_swing > 0:
        return None
    tt = t[start:]
    r = y[start:] - equilibrium[start:]
    length = float(tt[-1] - tt[0])
    dt = length / max(n - 1, 1)
    parts = np.array_split(np.arange(n), blocks)
    c = np.array([float(np.mean(tt[p])) for p in parts]) - float(tt[0])
    m = np.array([float(np.mean(r[p])) for p in parts])
    amplitude, tau, rms, slope = _approach(c, m, length, free_slope)
    if free_slope:
        # the equilibrium's pace over the rest is not known: the line fitted beside
        # the approach is taken off
        r = r - slope * (tt - tt[0])
        m = m - slope * c
    first, middle, last = _thirds(r)
    sign = 1.0 if first > 0 else -1.0
    move = sign * (first - last)
    se = _move_se(recorded, sigma, dt, n)
    floor = 0.0 if step is None else 2.0 * step * (dt if recorded == "velocity" else 1.0)
    early, late = sign * (first - middle), sign * (middle - last)
    scale = abs(move) if move != 0 else math.inf
    back = abs(amplitude) * math.exp(min((float(tt[0]) - stop_time) / tau, 50.0))
    held = math.nan
    if before >= blocks * MIN_BLOCK_SAMPLES:
        b1, _, b3 = _thirds(y[:before] - equilibrium[:before])
        span = float(t[before - 1] - t[0])
        moved = abs(b1 - b3) > HELD_Z * _move_se(recorded, sigma, dt, before)
        held = abs(b1 - b3) * length / span / scale if moved and span > 0 else 0.0
    return RestPath(
        start=float(tt[0]),
        end=float(tt[-1]),
        distance=abs(first),
        move=move,
        move_z=move / se,
        move_floor=floor,
        deceleration=early / late if late > 0 else math.inf,
        early=early,
        overshoot=float(np.max(-sign * m)) / scale,
        shape=rms / scale,
        line=_line_rms(c, m) / scale,
        time_constant=tau,
        at_stop=back / last_swing,
        pace=back / tau / (omega * last_swing),
        held=held,
        slope_share=abs(slope) * length / scale,
    )


def creep_towards_equilibrium(
    t: NDArray,
    y: NDArray,
    equilibrium: NDArray,
    start: int,
    *,
    recorded: str,
    sigma: float,
    stop_time: float,
    last_swing: float,
    omega: float,
    before: int = 0,
    step: float | None = None,
    free_slope: bool = False,
) -> ShapeCreep | None:
    """The creep of the rest ``t[start:]`` of a record with one channel, or None.

    Parameters
    ----------
    t : ndarray
        Time stamps [s], increasing.
    y : ndarray
        Displacement [length unit]: recorded, or integrated from the recorded velocity.
    equilibrium : ndarray
        The oscillation's equilibrium at each sample [length unit].
    start : int
        First sample of the rest after the stop.
    recorded : {"displacement", "velocity"}
        The channel recorded.
    sigma : float
        White noise of the recorded channel [length unit, or length unit/s].
    stop_time : float
        The stop [s].
    last_swing : float
        The last turning point's distance from the equilibrium [length unit].
    omega : float
        The oscillation's angular frequency [rad/s].
    before : int
        Samples of rest before the release (``t[:before]``), 0 when there is none.
    step : float, optional
        The recorded channel's digitiser step [its unit] (for a velocity, the move's
        step is that times the sample step).
    free_slope : bool
        The equilibrium's pace over the rest is not known (a velocity alone, whose
        offset during the motion is measured by the turning points' equilibrium only
        roughly): a line through the rest's start is fitted beside the approach and
        taken off before the conditions are tested, and may move the rest by at most
        :data:`SLOPE_SHARE` of the approach's move.

    Returns
    -------
    ShapeCreep or None
        None unless every condition of the module notes holds
        (:meth:`RestPath.creeps`).
    """
    path = rest_path(
        t,
        y,
        equilibrium,
        start,
        recorded=recorded,
        sigma=sigma,
        stop_time=stop_time,
        last_swing=last_swing,
        omega=omega,
        before=before,
        step=step,
        free_slope=free_slope,
    )
    if path is None or not path.creeps():
        return None
    return ShapeCreep(
        recorded,
        path.start,
        path.end,
        path.distance,
        path.move,
        path.move_z,
        path.time_constant,
        path.deceleration,
    )
