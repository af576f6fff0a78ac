"""A slow rig's free decay, integrated with ``solve_ivp`` independently of the package's
models: a 0.3 Hz pendulum bob recorded as a length at 20 Hz, written with five decimals
of metres (steps of 10 µm under 0.2 mm of noise), whose rest after the stop is 1.5
periods, shorter than the two-period blocks that judge where motion is.

x'' + 2ζΩx' + Ω²x = -Ω²x_c sign(x'), released from rest at ``X0_M`` after ``REST_S``
held; each half cycle (one sign of x') is integrated to its turning point (an event on
x' = 0), and the motion stops at the first turning point inside the static band
|x| <= x_s = (μ_s/μ_k) x_c, the record going on ``TAIL_S`` after it.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

#: The rig: frequency [Hz], damping ratio, kinetic and static friction coefficients,
#: load [N], mass [kg], release [m], sample rate [Hz], rest before and after [s].
F_HZ = 0.3
ZETA = 0.004
MU_K = 0.002
MU_S = 0.04
LOAD_N = 5.0
MASS_KG = 2.0
X0_M = 0.2
RATE_HZ = 20.0
REST_S = 3.0
TAIL_S = 5.0
#: Gaussian noise sd of the displacement [m].
NOISE_M = 2e-4
#: Friction displacements x_c and x_s [m].
STIFFNESS = MASS_KG * (2.0 * math.pi * F_HZ) ** 2
X_C = MU_K * LOAD_N / STIFFNESS
X_S = MU_S * LOAD_N / STIFFNESS
#: The sidecar of the record.
METADATA = {"load_N": LOAD_N, "mass_kg": MASS_KG, "natural_frequency_Hz": F_HZ}


def slow_decay(seed: int = 20, mu_s: float = MU_S) -> tuple[NDArray, NDArray, float]:
    """Time [s], displacement [m] (noise added, five decimals) and the stop's time [s]
    of the rig with static friction coefficient ``mu_s``."""
    omega = 2.0 * math.pi * F_HZ
    x_s = mu_s * LOAD_N / STIFFNESS
    start, position = REST_S, X0_M
    pieces = []
    while abs(position) > x_s:
        sign = -math.copysign(1.0, position)

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
        end = float(sol.t_events[0][0])
        pieces.append((start, end, sol.sol))
        start, position = end, float(sol.sol(end)[0])
    stop = start
    t = np.arange(round((stop + TAIL_S) * RATE_HZ)) / RATE_HZ
    x = np.full(t.size, X0_M)
    for a, b, path in pieces:
        inside = (t >= a) & (t < b)
        x[inside] = path(t[inside])[0]
    x[t >= stop] = position
    x = x + np.random.default_rng(seed).normal(0.0, NOISE_M, t.size)
    return t, np.round(x, 5), stop


def write_slow_decay(folder: Path, seed: int = 20, mu_s: float = MU_S) -> tuple[Path, float]:
    """The record (:func:`slow_decay`) as a CSV (time_s, displacement_m) with its JSON
    sidecar; its path and the stop's time [s]."""
    import json

    t, x, stop = slow_decay(seed, mu_s)
    path = folder / f"slow_pendulum_{seed}_{mu_s:g}.csv"
    rows = "\n".join(f"{a:.3f},{b:.5f}" for a, b in zip(t, x, strict=True))
    path.write_text("time_s,displacement_m\n" + rows + "\n")
    path.with_suffix(".json").write_text(json.dumps(METADATA))
    return path, stop
