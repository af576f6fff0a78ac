"""An accelerometer's record of a free decay with viscous damping and Coulomb friction,
integrated with ``solve_ivp`` independently of the package's models.

x'' = -2ζΩx' - Ω²(x + x_c sgn x'), held at x₀ and released at ``hold``; each half cycle
(one sign of x') is integrated to its turning point (an event on x' = 0), and the
motion stops at the first turning point inside the friction band |x| <= x_c (static
friction equal to kinetic). The acceleration is sampled as an integrating anti-alias
filter samples it, its mean over each sample interval ((v(t + Δt/2) - v(t - Δt/2))/Δt,
from the motion solved on a grid of half the step), with white noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp


@dataclass(frozen=True)
class Decay:
    """The oscillator [Hz, -, m, m], the sampling [Hz], the hold and the record [s], and
    the acceleration's noise sd [m/s²]."""

    f0: float = 60.0
    zeta: float = 0.01
    friction: float = 2e-6
    x0: float = 1e-4
    rate: float = 5000.0
    hold: float = 0.3
    duration: float = 2.0
    noise: float = 0.02


def _motion(case: Decay, t: NDArray) -> tuple[NDArray, NDArray, float]:
    """Displacement and velocity at times ``t``, and the time the motion stops [s]."""
    w = 2.0 * math.pi * case.f0
    x = np.full(t.size, case.x0)
    v = np.zeros(t.size)
    y, t0 = case.x0, case.hold
    filled = int(np.searchsorted(t, case.hold, side="left"))
    while filled < t.size:
        if abs(y) <= case.friction:
            x[filled:] = y
            return x, v, t0
        sgn = -1.0 if y > 0 else 1.0

        def rhs(_t: float, u: NDArray, sgn: float = sgn) -> list[float]:
            return [u[1], -2.0 * case.zeta * w * u[1] - w * w * (u[0] + sgn * case.friction)]

        def turned(_t: float, u: NDArray) -> float:
            return u[1]

        turned.terminal, turned.direction = True, -sgn
        sol = solve_ivp(
            rhs,
            (t0, t0 + 1.0 / case.f0),
            [y, 0.0],
            method="DOP853",
            rtol=1e-11,
            atol=1e-15,
            events=turned,
            dense_output=True,
        )
        t1 = float(sol.t_events[0][0])
        stop = int(np.searchsorted(t, t1, side="right"))
        x[filled:stop], v[filled:stop] = sol.sol(t[filled:stop])
        filled, y, t0 = stop, float(sol.y_events[0][0][0]), t1
    return x, v, math.inf


def accelerometer(case: Decay, seed: int) -> tuple[NDArray, NDArray, NDArray, float]:
    """Time [s], measured acceleration [m/s²], true velocity [m/s] at those times, and
    the time the motion stops [s] (inf: it goes on past the record)."""
    dt = 1.0 / case.rate
    fine = np.arange(0.0, case.duration + dt, 0.5 * dt)
    _, v, stopped = _motion(case, fine)
    t = fine[1:-1:2]  # centres of the sample intervals [k Δt, (k + 1) Δt]
    a = (v[2::2] - v[0:-2:2])[: t.size] / dt
    rng = np.random.default_rng(seed)
    return t, a + rng.normal(0.0, case.noise, t.size), v[1:-1:2], stopped
