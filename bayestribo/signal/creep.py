"""A rest after the stop in which the mass still moves (a creep).

A friction that vanishes towards zero speed (a lubricated contact, a Stribeck friction
regularised at rest, a viscoelastic pad) does not hold the mass where its last half
cycle ends: it creeps on towards the spring's equilibrium at a speed far below the
oscillation's, for seconds. The end of motion is found where the velocity's swings
sink below their threshold, so the creep falls into the rest after the stop, and the
noise measured there holds it: on a 5 Hz record with a friction regularised below
0.1 mm/s the displacement's noise at rest came out 94 times the recorded noise, and a
law that misfits the decay passed its misfit test (exit 0, ΔE(A) off the truth by 10 %
at the smallest swings).

The mass moves when both recorded channels say so: the displacement's least-squares
line over the rest changes by more than :data:`CREEP_Z` standard errors of white noise
(taken from its 4th differences, which a slow creep does not reach), the velocity's
mean differs from zero by as many, and the two agree (the same sign, the line's slope
within a factor :data:`CREEP_AGREEMENT` of the mean velocity). A sensor's offset moves
one channel and not the other, a coloured noise moves them independently; a creep
moves both as one. With one channel recorded, the creep is told by its path instead
(:mod:`bayestribo.signal.creep_shape`: towards the oscillation's equilibrium, slowing
down, from inside the last swing, not in a rest before the release).

No registered law's motion creeps (a friction sticks where its swings end, a drag
oscillates on), so a creep is a misfit of the law at low speed: the
:class:`~bayestribo.errors.CreepWarning` is a :class:`~bayestribo.errors.MisfitWarning`
(``bayestribo fit`` exits 1) and the answer is the turning points' ΔE(A). On the 5 Hz
records of ``benchmarks/stribeck_verdict.py --rig creep`` with the creep's noise taken
out, a weak Stribeck excess (a_Δ = 0.3 a_k) passed ``law="auto"``'s checks as
``coulomb+power`` with a band 23 sd off the true ΔE at the smallest swing, where the
turning points' band held it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bayestribo._stamps import stamp
from bayestribo.errors import CreepWarning
from bayestribo.signal.peaks import estimate_noise

__all__ = ["CREEP_AGREEMENT", "CREEP_Z", "Creep", "CreepWarning", "creeping_rest"]

#: Standard errors of white noise by which the displacement's change over the rest and
#: the velocity's mean must both exceed zero (a Gaussian exceeds 8 with probability
#: 1e-15).
CREEP_Z = 8.0
#: Largest ratio of the displacement's slope to the velocity's mean (either way).
CREEP_AGREEMENT = 2.0
#: Fewest samples a rest must hold to be tested.
MIN_SAMPLES = 20


@dataclass(frozen=True)
class Creep:
    """What moved in the rest after the stop.

    Attributes
    ----------
    start, end : float
        The rest tested [s].
    slope : float
        Least-squares slope of the displacement over it [length unit/s].
    slope_z : float
        That slope in standard errors of white noise.
    mean_velocity : float
        The velocity's mean over it [length unit/s].
    velocity_z : float
        That mean in standard errors of white noise.
    """

    start: float
    end: float
    slope: float
    slope_z: float
    mean_velocity: float
    velocity_z: float

    def describe(self) -> str:
        """One sentence for the warning: the times, the drift and its speed."""
        return (
            f"from t = {stamp(self.start, self.end - self.start)} to "
            f"{stamp(self.end, self.end - self.start)} the displacement moves at "
            f"{self.slope:.3g} per s ({self.slope_z:.0f} standard errors of its noise) and "
            f"the velocity's mean is {self.mean_velocity:.3g} ({self.velocity_z:.0f} "
            "standard errors): the mass creeps on after its last half cycle"
        )


def creeping_rest(t: NDArray, x: NDArray, v: NDArray, start: int) -> Creep | None:
    """The creep in the rest ``t[start:]`` of a record with both channels, or None.

    Parameters
    ----------
    t : ndarray
        Time stamps [s], increasing.
    x : ndarray
        Displacement [length unit], recorded (not derived).
    v : ndarray
        Velocity [length unit/s], recorded (not derived).
    start : int
        First sample of the rest after the stop.

    Returns
    -------
    Creep or None
        None when the rest is shorter than :data:`MIN_SAMPLES` samples, or when either
        channel is still, or they disagree (see the module notes).
    """
    tt, xx, vv = t[start:], x[start:], v[start:]
    n = tt.size
    if n < MIN_SAMPLES:
        return None
    sigma_x, sigma_v = estimate_noise(xx), estimate_noise(vv)
    if not (sigma_x > 0 and sigma_v > 0):
        return None
    centred = tt - float(np.mean(tt))
    spread = float(centred @ centred)
    if not spread > 0:
        return None
    slope = float(centred @ (xx - float(np.mean(xx)))) / spread
    slope_z = abs(slope) / (sigma_x / math.sqrt(spread))
    mean_v = float(np.mean(vv))
    velocity_z = abs(mean_v) / (sigma_v / math.sqrt(n))
    if slope_z <= CREEP_Z or velocity_z <= CREEP_Z or slope * mean_v <= 0:
        return None
    ratio = slope / mean_v
    if not 1.0 / CREEP_AGREEMENT <= ratio <= CREEP_AGREEMENT:
        return None
    return Creep(float(tt[0]), float(tt[-1]), slope, slope_z, mean_v, velocity_z)
