"""A pendulum's free decay with viscous damping and Coulomb friction, integrated with
``solve_ivp`` independently of the package's models: the record the adequacy checks
on a nonlinear restoring force are tested and benchmarked on.

θ'' = -(g/L) sin θ - b θ' - (g/L) θ_c sgn θ'  (b = 2ζω₀, ω₀² = g/L, θ_c the friction as
an angle [rad]), released from rest at θ₀; each half cycle (one sign of θ') is
integrated to its turning point (an event on θ' = 0), and the motion stops at the first
turning point inside the friction band |sin θ| <= θ_c (static friction equal to
kinetic). The angle [rad] and the angular velocity [rad/s] are recorded with white
noise.

A Duffing spring, x'' = -ω₀²(x + βx³) - 2ζω₀x' - ω₀² x_c sgn x', is simulated the same
way (``beta`` given).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp


@dataclass(frozen=True)
class Swing:
    """The oscillator: small-swing frequency ``f0`` [Hz], damping ratio ``zeta`` [-],
    friction ``friction`` [rad, or the length unit], release ``x0`` [rad or length unit],
    ``beta`` (None: the pendulum's sin θ; else a Duffing spring's β [length unit⁻²]),
    sampling ``rate`` [Hz], ``duration`` [s], noise sd of the displacement ``noise``
    [rad or length unit] and of the velocity ``noise_v`` [per s]."""

    f0: float = 0.7
    zeta: float = 0.004
    friction: float = 0.004
    x0: float = 1.4
    beta: float | None = None
    rate: float = 200.0
    duration: float = 40.0
    noise: float = 1e-3
    noise_v: float = 4e-3

    def spring(self, x: float) -> float:
        """V'(x): sin x (pendulum) or x + βx³."""
        return math.sin(x) if self.beta is None else x + self.beta * x**3


def swing(case: Swing, seed: int) -> tuple[NDArray, NDArray, NDArray]:
    """Time [s], displacement and velocity of ``case`` with noise drawn from ``seed``:
    rest after the motion stops (within ``duration``)."""
    w = 2.0 * math.pi * case.f0
    t = np.arange(0.0, case.duration, 1.0 / case.rate)
    x = np.empty_like(t)
    v = np.zeros_like(t)
    y, t0, filled = float(case.x0), 0.0, 0
    while filled < t.size:
        if abs(case.spring(y)) <= case.friction:
            x[filled:], v[filled:] = y, 0.0  # at rest
            break
        sgn = -1.0 if y > 0 else 1.0

        def rhs(_t: float, u: NDArray, sgn: float = sgn) -> list[float]:
            force = case.spring(u[0]) + case.friction * sgn
            return [u[1], -2.0 * case.zeta * w * u[1] - w * w * force]

        def turned(_t: float, u: NDArray) -> float:
            return u[1]

        turned.terminal, turned.direction = True, -sgn
        sol = solve_ivp(
            rhs,
            (t0, t0 + 10.0 / case.f0),
            [y, 0.0],
            method="DOP853",
            rtol=1e-10,
            atol=1e-12,
            events=turned,
            dense_output=True,
        )
        t1 = float(sol.t_events[0][0])
        stop = int(np.searchsorted(t, t1, side="right"))
        states = sol.sol(t[filled:stop])
        x[filled:stop], v[filled:stop] = states[0], states[1]
        filled, y, t0 = stop, float(sol.y_events[0][0][0]), t1
    rng = np.random.default_rng(seed)
    return (
        t,
        x + rng.normal(0.0, case.noise, t.size),
        v + rng.normal(0.0, case.noise_v, t.size),
    )
