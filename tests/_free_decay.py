"""An oscillator's free decay with viscous damping and Coulomb friction, integrated with
``solve_ivp`` independently of the package's models: the record the file-format tests
write in each format and fit.

x'' + 2ζΩx' + Ω²x = -Ω²x_c sign(x'), released from rest at x0 at ``RELEASE_S`` and held
at rest before; each half cycle (one sign of x') is integrated to its turning point
(an event on x' = 0), and the motion stops at the first turning point inside the
friction band |x| <= x_c (static friction equal to kinetic).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

#: The oscillator: frequency [Hz], damping ratio, friction displacement and release
#: displacement [fractions of full scale, or any length unit].
F_HZ = 20.0
ZETA = 0.006
X_C = 0.008
X0 = 0.8
RATE_HZ = 2000
RELEASE_S = 0.1
DURATION_S = 1.2
#: Gaussian noise sd [length unit]: a sensor's noise, larger than a 16-bit step.
NOISE = 2e-4


@dataclass(frozen=True)
class Decay:
    """The record: time [s], displacement, velocity and acceleration [length unit, /s,
    /s²]."""

    time: NDArray
    displacement: NDArray
    velocity: NDArray
    acceleration: NDArray


def free_decay(seed: int = 7, noise: float = NOISE) -> Decay:
    """The record at ``RATE_HZ``: rest, release, decay to a stop, rest; Gaussian noise
    of sd ``noise`` added to the displacement (``Ω noise`` to the velocity, ``Ω² noise``
    to the acceleration)."""
    omega = 2.0 * math.pi * F_HZ
    t = np.arange(int(DURATION_S * RATE_HZ)) / RATE_HZ
    x = np.full(t.size, X0)
    v = np.zeros(t.size)
    a = np.zeros(t.size)
    start, position = RELEASE_S, X0
    while abs(position) > X_C and start < t[-1]:
        sign = -math.copysign(1.0, position)  # the direction of this half cycle

        def rhs(_t: float, s: NDArray, sign: float = sign) -> list[float]:
            return [s[1], -2.0 * ZETA * omega * s[1] - omega**2 * (s[0] + X_C * sign)]

        def turned(_t: float, s: NDArray) -> float:
            return s[1]

        turned.terminal, turned.direction = True, -sign
        sol = solve_ivp(
            rhs,
            (start, start + 1.0 / F_HZ),
            [position, 0.0],
            method="DOP853",
            rtol=1e-11,
            atol=1e-13,
            events=turned,
            dense_output=True,
        )
        end = float(sol.t_events[0][0]) if sol.t_events[0].size else float(sol.t[-1])
        inside = (t >= start) & (t < end)
        states = sol.sol(t[inside])
        x[inside], v[inside] = states[0], states[1]
        a[inside] = [rhs(0.0, state)[1] for state in states.T]
        start, position = end, float(sol.sol(end)[0])
        x[t >= end], v[t >= end] = position, 0.0
    rng = np.random.default_rng(seed)
    return Decay(
        t,
        x + rng.normal(0.0, noise, t.size),
        v + rng.normal(0.0, omega * noise, t.size),
        a + rng.normal(0.0, omega**2 * noise, t.size),
    )


#: The metadata a fit of the record needs: its length unit is the file's.
METADATA = {"length_unit": "arbitrary", "natural_frequency_Hz": F_HZ, "gain_uncertainty": 0.0}
