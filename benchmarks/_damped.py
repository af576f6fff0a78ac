"""Independent simulator of a free decay with viscous, Coulomb and quadratic damping.

Nothing here comes from the package: ``scipy.integrate.solve_ivp`` integrates

    x'' + 2ζω x' + β |x'| x' + ω² x_c sgn(x') + ω² x = 0

half cycle by half cycle (the friction's sign is constant between velocity zeros) from
``x0`` at rest, sticking at the first turning point inside ±``stick`` x_c. The true
law-free answer is read off the simulation's own energy: the half cycle from the
turning point ``x_n`` to ``x_n+1`` loses ``k (x_n² − x_n+1²)/2``, so ΔE/k per cycle at
its swing ``(|x_n| + |x_n+1|)/2`` is ``x_n² − x_n+1²`` (:func:`true_dissipation`
interpolates it, log-log, at any swing).

Shared by ``benchmarks/coarse_dissipation.py``; ``tests/test_coarse_dissipation.py``
carries its own copy (tests do not import benchmarks).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

__all__ = ["DAMPINGS", "Decay", "quantise", "simulate", "true_dissipation"]

#: Dampings tried, as (ζ, x_c [m], β [1/m]) on a 32.6 Hz oscillator from 2 mm: each
#: decays to a tenth of its swing in some 10 to 25 cycles, the strong friction stops it in
#: six (its swing falls by 8 % of itself in a half cycle at 1 mm).
DAMPINGS: dict[str, tuple[float, float, float]] = {
    "viscous": (0.03, 0.0, 0.0),
    "coulomb": (0.0, 25e-6, 0.0),
    "quadratic": (0.0, 0.0, 80.0),
    "mixed": (0.01, 8e-6, 30.0),
    "strong-coulomb": (0.0, 80e-6, 0.0),
}


@dataclass(frozen=True)
class Decay:
    """A simulated record and its true turning points.

    Attributes
    ----------
    t, x, v : ndarray
        Time [s], displacement [m] and velocity [m/s] at the sample rate.
    turning : ndarray
        The motion's turning points [m], the release's first.
    """

    t: NDArray
    x: NDArray
    v: NDArray
    turning: NDArray


def simulate(
    zeta: float,
    xc: float,
    beta: float,
    *,
    f: float = 32.6,
    x0: float = 2e-3,
    fs: float = 10_000.0,
    rest_before: float = 0.1,
    duration: float = 1.2,
    stick: float = 1.36,
    smallest: float = 2e-6,
) -> Decay:
    """Integrate the motion from ``x0`` at rest and sample it at ``fs``.

    The record holds ``rest_before`` s at ``x0``, the motion from the release, and rest
    at the stop up to ``duration`` s in all; a motion that has not stopped when its swing
    falls below ``smallest`` [m] (viscous or quadratic damping) ends there, at rest.
    """
    w = 2 * math.pi * f

    def rhs(_: float, s: NDArray, sgn: float) -> list[float]:
        x, v = s
        return [v, -(w**2) * x - 2 * zeta * w * v - beta * abs(v) * v - w**2 * xc * sgn]

    t = np.arange(0.0, duration, 1.0 / fs)
    x = np.full(t.size, x0)
    v = np.zeros(t.size)
    t0, state, turning = rest_before, np.array([x0, 0.0]), [x0]
    while True:
        sgn = -math.copysign(1.0, state[0])  # moving towards the other side
        if abs(state[0]) <= stick * xc or abs(state[0]) < smallest:
            break

        def turn(_: float, s: NDArray, sgn: float) -> float:
            return s[1]

        turn.terminal = True
        turn.direction = -sgn  # v leaves 0 with the sign sgn and comes back to it
        sol = solve_ivp(
            rhs,
            (0.0, 1.0 / f),
            state,
            args=(sgn,),
            events=turn,
            dense_output=True,
            rtol=1e-10,
            atol=1e-13,
            first_step=1e-7,
        )
        if not sol.t_events[0].size:
            raise RuntimeError("no turning point within a period")
        te = float(sol.t_events[0][-1])
        m = (t >= t0) & (t < t0 + te)
        if m.any():
            s = sol.sol(t[m] - t0)
            x[m], v[m] = s[0], s[1]
        state = np.array([float(sol.y_events[0][-1][0]), 0.0])
        t0 += te
        if abs(state[0]) > abs(turning[-1]) or state[0] * turning[-1] > 0:
            break  # stuck before crossing: the friction held it
        turning.append(float(state[0]))
        if t0 >= t[-1]:
            break
    x[t >= t0] = state[0]
    v[t >= t0] = 0.0
    return Decay(t, x, v, np.asarray(turning))


def true_dissipation(turning: NDArray, amplitudes: NDArray) -> NDArray:
    """ΔE/k per cycle [m²] at the swings ``amplitudes`` [m], from the true turning points.

    Each half cycle gives ``x_n² − x_n+1²`` at ``(|x_n| + |x_n+1|)/2``; between them it is
    interpolated linearly in log-log (NaN outside the swings the motion had).
    """
    a = np.abs(np.asarray(turning, dtype=float))
    swing = 0.5 * (a[:-1] + a[1:])
    loss = a[:-1] ** 2 - a[1:] ** 2
    order = np.argsort(swing)
    amps = np.asarray(amplitudes, dtype=float)
    out = np.exp(
        np.interp(
            np.log(amps), np.log(swing[order]), np.log(loss[order]), left=np.nan, right=np.nan
        )
    )
    return out


def quantise(
    decay: Decay,
    steps: float,
    placement: tuple[float, float],
    noise: float,
    rng: np.random.Generator,
) -> tuple[NDArray, NDArray]:
    """Both channels rounded to 1/``steps`` of their swing over the record, levels placed
    ``placement`` steps off the zero, after white noise of ``noise`` steps."""
    out = []
    for s, u in zip((decay.x, decay.v), placement, strict=True):
        q = float(np.ptp(s)) / steps
        r = s + noise * q * rng.standard_normal(s.size)
        out.append((np.round(r / q + u) - u) * q)
    return out[0], out[1]
