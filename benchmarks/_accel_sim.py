"""Independent simulator of an accelerometer's free-decay record, for ``acceleration.py``.

Nothing here comes from :mod:`bayestribo`: the motion of a spring-mass oscillator

    m ẍ + c ẋ + k x + μ_k N sgn ẋ + m q ẋ|ẋ| = 0,    c = 2ζ m Ω, Ω² = k/m,

is integrated with :func:`scipy.integrate.solve_ivp` (DOP853, rtol 1e-10) half cycle by
half cycle, each ending on the event ẋ = 0; at a turning point the contact sticks when
|k x| <= μ_s N. The record is the acceleration a = ẍ as an accelerometer with an
anti-alias filter samples it: the mean of ẍ over each sample interval,
(ẋ(t + Δt/2) − ẋ(t − Δt/2))/Δt (the acceleration jumps at the release, at each turn
of the friction and at the stop), times the sensor's gain (its sensitivity's error,
1 for an exact sensor), plus a constant bias and white noise, with rest
before the release and after the stop (a drag-only motion, which never stops, is
recorded until it has faded into the noise).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

G = 9.80665


@dataclass(frozen=True)
class Rig:
    """A horizontal spring-mass rig sliding on a flat (load N = m g)."""

    mass: float = 0.25  # kg
    f_Hz: float = 2.5  # natural frequency
    zeta: float = 0.005
    mu_k: float = 0.0
    mu_s_ratio: float = 1.3
    q: float = 0.0  # quadratic drag per unit mass [1/m]

    @property
    def omega(self) -> float:
        return 2.0 * math.pi * self.f_Hz

    @property
    def load(self) -> float:
        return self.mass * G

    def accel(self, x: float, v: float) -> float:
        s = math.copysign(1.0, v) if v != 0.0 else 0.0
        return (
            -(self.omega**2) * x
            - 2.0 * self.zeta * self.omega * v
            - self.mu_k * G * s
            - self.q * v * abs(v)
        )


def motion(rig: Rig, x0: float, duration: float) -> tuple[list, float | None]:
    """Half cycles as solve_ivp dense solutions from x0 at rest; the stop time or None."""
    pieces = []
    t0, x = 0.0, x0
    while t0 < duration:
        if rig.mu_k > 0 and rig.omega**2 * abs(x) <= rig.mu_s_ratio * rig.mu_k * G:
            return pieces, t0  # sticks
        sign = -math.copysign(1.0, x)  # direction of the half cycle

        def rhs(t, y, sign=sign):
            # the friction opposes the half cycle's motion up to its turning point and
            # a step beyond it: a friction that flipped with the velocity's sign there
            # held a turn inside the sticking zone at v = 0, which the solver chattered
            # about (steps of 1e-12 s, the event never found)
            v = y[1] if y[1] * sign > 0.0 else sign * 1e-300
            return [y[1], rig.accel(y[0], v)]

        def turn(t, y):
            return y[1]

        turn.terminal, turn.direction = True, -sign
        # start just off rest: the velocity grows in the direction `sign`
        sol = solve_ivp(
            rhs,
            (t0, min(duration, t0 + 2.0 / rig.f_Hz)),
            [x, 0.0],
            method="DOP853",
            rtol=1e-10,
            atol=1e-13,
            events=turn,
            dense_output=True,
            first_step=1e-6,
        )
        pieces.append((t0, sol.t[-1], sol.sol))
        if sol.status != 1:
            return pieces, None
        t0, x = float(sol.t[-1]), float(sol.y[0, -1])
    return pieces, None


def record(
    rig: Rig,
    x0: float,
    *,
    rate: float = 200.0,
    rest_before: float = 2.0,
    rest_after: float = 3.0,
    duration: float = 30.0,
    noise: float = 0.02,
    bias: float = 0.2,
    seed: int = 0,
    gain: float = 1.0,
) -> dict:
    """Time [s], acceleration with gain, bias and noise [m/s²], and the truth.

    ``gain`` multiplies the acceleration the sensor reads (a sensitivity off by
    ``gain - 1``): every length integrated from the record is ``gain`` times the motion's.
    """
    pieces, stop = motion(rig, x0, duration)
    # a motion that does not stop (drag only) is recorded until ``duration``: it fades
    # into the noise there, and is never cut short by a rest it does not reach
    end = stop + rest_after if stop is not None else pieces[-1][1]
    t = np.arange(0.0, rest_before + end, 1.0 / rate)
    tau = t - rest_before

    def state(times):
        x = np.full_like(times, x0)
        v = np.zeros_like(times)
        for start, finish, sol in pieces:
            inside = (times >= start) & (times < finish)
            y = sol(times[inside])
            x[inside], v[inside] = y[0], y[1]
        after = times >= pieces[-1][1]
        x[after] = pieces[-1][2](pieces[-1][1])[0]
        return x, v

    x, v = state(tau)
    dt = 1.0 / rate
    a = (state(tau + 0.5 * dt)[1] - state(tau - 0.5 * dt)[1]) / dt
    rng = np.random.default_rng(seed)
    measured = gain * a + bias + noise * rng.standard_normal(t.size)
    return {"time": t, "acceleration": measured, "x": x, "v": v, "a": a, "stop": stop}
