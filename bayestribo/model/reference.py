"""Slow, obviously right reference: the equation of motion integrated numerically.

Eq. 7 is integrated with :func:`scipy.integrate.solve_ivp` one half cycle at a time,
each half cycle ending on a velocity-zero event, with the stick rule of Eq. 8 applied
at every turning point. Nothing here shares code with :mod:`bayestribo.model.exact`:
it exists to check the closed forms (tests) and to time the direct approach
(benchmarks).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import quad, solve_ivp

__all__ = ["OdeSolution", "ode_pi", "ode_solve"]


@dataclass
class OdeSolution:
    """Piecewise numerical solution: one dense ``solve_ivp`` output per half cycle."""

    segments: list = field(default_factory=list)
    turning_times: list[float] = field(default_factory=list)
    turning_positions: list[float] = field(default_factory=list)
    stop_time: float = np.inf
    rest_position: float = np.nan

    def response(self, tau: ArrayLike) -> tuple[NDArray, NDArray]:
        """y(τ) and y'(τ) from the dense outputs (rest position after the stop)."""
        t = np.atleast_1d(np.asarray(tau, dtype=float))
        y = np.full(t.shape, self.rest_position)
        yp = np.zeros(t.shape)
        for seg in self.segments:
            inside = (t >= seg.t[0]) & (t <= seg.t[-1])
            if np.any(inside):
                val = seg.sol(t[inside])
                y[inside], yp[inside] = val[0], val[1]
        return y, yp

    def energy(self, tau: ArrayLike) -> NDArray:
        """E(τ) = (y² + y'²)/2."""
        y, yp = self.response(tau)
        return 0.5 * (y * y + yp * yp)


def ode_solve(
    y0: float,
    zeta: float,
    mu_k: float,
    mu_s: float,
    yp0: float = 0.0,
    tau_max: float = np.inf,
    rtol: float = 1e-12,
    atol: float = 1e-13,
) -> OdeSolution:
    """Integrate y'' + 2ζy' + y = -μ_k sgn(y') half cycle by half cycle (Eq. 7-8).

    Parameters
    ----------
    y0, zeta, mu_k, mu_s, yp0 : float
        Initial state and parameters, dimensionless.
    tau_max : float
        Stop integrating after this τ even if the motion goes on.
    rtol, atol : float
        Tolerances passed to ``solve_ivp`` (DOP853).
    """
    out = OdeSolution()
    t, state = 0.0, np.array([y0, yp0], dtype=float)
    while t < tau_max:
        if state[1] == 0.0:
            if abs(state[0]) <= mu_s:
                out.stop_time, out.rest_position = t, float(state[0])
                out.turning_times.append(t)
                out.turning_positions.append(float(state[0]))
                return out
            out.turning_times.append(t)
            out.turning_positions.append(float(state[0]))
            direction = -np.sign(state[0])
        else:
            direction = np.sign(state[1])

        def rhs(_t: float, s: NDArray, d: float = direction) -> list[float]:
            return [s[1], -2.0 * zeta * s[1] - s[0] - mu_k * d]

        def turning(_t: float, s: NDArray) -> float:
            return s[1]

        turning.terminal = True
        turning.direction = -direction
        # A half cycle lasts π/√(1-ζ²); leave margin for the event.
        span = min(t + 1.5 * np.pi / np.sqrt(1.0 - zeta**2) + 1.0, tau_max)
        sol = solve_ivp(
            rhs,
            (t, span),
            state,
            method="DOP853",
            events=turning,
            rtol=rtol,
            atol=atol,
            dense_output=True,
        )
        out.segments.append(sol)
        if sol.t_events[0].size == 0:
            break
        t = float(sol.t_events[0][0])
        state = np.array([sol.y_events[0][0][0], 0.0])
    return out


def ode_pi(solution: OdeSolution, tau: ArrayLike, tau_end: float = np.inf) -> NDArray:
    """Π(τ) by adaptive quadrature of E over each half cycle of an ODE solution."""
    end = min(solution.stop_time, tau_end)
    values = []
    for t0 in np.atleast_1d(np.asarray(tau, dtype=float)):
        total = 0.0
        for seg in solution.segments:
            a, b = max(seg.t[0], t0), min(seg.t[-1], end)
            if b > a:
                total += quad(
                    lambda u, s=seg: 0.5 * float(np.sum(s.sol(u) ** 2)),
                    a,
                    b,
                    epsabs=0.0,
                    epsrel=1e-12,
                    limit=200,
                )[0]
        values.append(total)
    return np.asarray(values)
