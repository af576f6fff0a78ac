"""Independent simulator of a Stribeck friction regularised at rest, for
``benchmarks/stribeck_verdict.py --rig creep``.

Nothing here comes from the package: the motion per unit mass (the record of the
issue the ``stribeck`` branches answered: a 5 Hz oscillator recorded without metadata),

    ẍ = -Ω²x - 2ζΩẋ - (a_k + a_Δ exp(-(|ẋ|/v_s)^δ)) tanh(ẋ/v_r),   v_r = 10⁻⁴ m/s,

is integrated by :func:`scipy.integrate.solve_ivp` (LSODA, rtol 1e-9) from x₀ at rest
and sampled at 500 Hz for 6 s with white noise of 5e-7 m and 5e-5 m/s. Below v_r the
friction is viscous: the mass does not stick where its swings end but creeps towards
the equilibrium for the rest of the record.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

__all__ = ["FS", "NOISE", "OMEGA", "CreepTruth", "simulate", "true_dissipation"]

OMEGA = 2.0 * math.pi * 5.0
FS = 500.0
DURATION_S = 6.0
NOISE = (5e-7, 5e-5)  # m, m/s
V_R = 1e-4  # m/s: the friction's sign as tanh(v/V_R)


@dataclass(frozen=True)
class CreepTruth:
    """ζ, a_k and a_Δ [m/s²], v_s [m/s], δ and x₀ [m] of one record."""

    zeta: float
    a_k: float
    a_delta: float
    v_s: float
    delta: float
    x0: float

    def acceleration(self, x: float, v: float) -> float:
        """ẍ [m/s²] at displacement x [m] and velocity v [m/s]."""
        friction = self.a_k + self.a_delta * math.exp(-((abs(v) / self.v_s) ** self.delta))
        return -(OMEGA**2) * x - 2.0 * self.zeta * OMEGA * v - friction * math.tanh(v / V_R)


def simulate(truth: CreepTruth, seed: object) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """t [s], displacement [m] and velocity [m/s] of one noisy record."""
    t = np.arange(0.0, DURATION_S, 1.0 / FS)
    sol = solve_ivp(
        lambda _t, s: [s[1], truth.acceleration(s[0], s[1])],
        (0.0, DURATION_S),
        [truth.x0, 0.0],
        t_eval=t,
        method="LSODA",
        rtol=1e-9,
        atol=1e-12,
    )
    rng = np.random.default_rng(seed)
    x = sol.y[0] + rng.normal(0.0, NOISE[0], t.size)
    v = sol.y[1] + rng.normal(0.0, NOISE[1], t.size)
    return t, x, v


def _half_cycle_end(truth: CreepTruth, a: float) -> float:
    """|x| [m] where the half cycle from rest at x = a > 0 turns."""

    def turned(_t: float, s: np.ndarray) -> float:
        return s[1]

    turned.terminal, turned.direction = True, 1.0
    sol = solve_ivp(
        lambda _t, s: [s[1], truth.acceleration(s[0], s[1])],
        (0.0, 2.0 * math.pi / OMEGA),
        [a, 0.0],
        method="LSODA",
        events=turned,
        rtol=1e-11,
        atol=1e-15,
    )
    if sol.t_events[0].size == 0:
        raise RuntimeError(f"no turning point within a period from a = {a:g} m")
    return -float(sol.y_events[0][0][0])


def true_dissipation(truth: CreepTruth, amplitude_m: np.ndarray) -> np.ndarray:
    """ΔE(A)/k [m²] at each swing A: a_s² - a_e² over the half cycle of the true motion
    from rest at a_s to its turning point a_e with (a_s + a_e)/2 = A (a_s by Brent's
    method), the package's ΔE(A) of a record without mass and stiffness."""
    out = []
    for amp in np.atleast_1d(np.asarray(amplitude_m, dtype=float)):
        a_s = brentq(
            lambda a, amp=amp: 0.5 * (a + _half_cycle_end(truth, a)) - amp,
            amp,
            2.0 * amp,
            xtol=1e-14 * amp,
        )
        out.append(a_s**2 - _half_cycle_end(truth, a_s) ** 2)
    return np.array(out)
