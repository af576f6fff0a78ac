"""An accelerometer's record of a free decay with viscous damping and Coulomb friction,
from the independent ``solve_ivp`` simulator of ``tests/_law_recording.py``.

x'' = -2ζΩx' - Ω²(x + x_c sgn x'), held at x₀ and released at ``hold``, sticking at the
first turning point inside the friction band |x| <= x_c (static friction equal to
kinetic). The acceleration is sampled as an integrating anti-alias filter samples it,
its mean over each sample interval ((v(t + Δt/2) - v(t - Δt/2))/Δt, from the motion
recorded at twice the rate with noise of 1e-15), with white noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from _law_recording import law_recording
from numpy.typing import NDArray


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


def accelerometer(case: Decay, seed: int) -> tuple[NDArray, NDArray, NDArray, float]:
    """Time [s], measured acceleration [m/s²], true velocity [m/s] at those times, and
    the time the motion stops [s] (to half a sample step; inf: it goes on past the
    record)."""
    omega = 2.0 * math.pi * case.f0
    fine = law_recording(
        lambda v: 2.0 * case.zeta * omega * v,
        friction=case.friction * omega**2,
        static_ratio=1.0,
        x0=case.x0,
        frequency_Hz=case.f0,
        load_N=None,
        sample_rate_Hz=2.0 * case.rate,
        noise_x=1e-15,  # the least resolution a run takes: no noise to speak of
        noise_v=1e-15,
        rest_before_s=case.hold,
        duration_s=case.duration - case.hold,
    )
    tf, v = fine.time, fine.velocity
    moving = np.flatnonzero(np.abs(v) > 1e-12)
    stopped = math.inf if moving[-1] >= v.size - 2 else float(tf[moving[-1] + 1])
    t = tf[1:-1:2]  # centres of the sample intervals [k Δt, (k + 1) Δt]
    a = (v[2::2] - v[0:-2:2])[: t.size] * case.rate
    rng = np.random.default_rng(seed)
    return t, a + rng.normal(0.0, case.noise, t.size), v[1:-1:2], stopped
