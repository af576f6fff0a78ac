"""Reference free-decay signals for the estimator tests, checked against an ODE solver.

``exact_signal`` is a direct, independent transcription of the piecewise solution
(Rigaud et al. 2010, Eq. 16-17, 19): half-cycle by half-cycle, arcs centred at
±μ_k, sticking at the first turning point with |Y_n| <= μ_s. It is verified here
against scipy's ODE integrator so that the estimator tests rest on checked signals.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bayestribo.signal.peaks import Peaks

__all__ = ["exact_signal", "exact_turning_points"]


def exact_turning_points(
    y0: float, zeta: float, mu_k: float, mu_s: float | None = None, max_count: int = 100_000
) -> tuple[np.ndarray, np.ndarray, bool]:
    """Turning points (τ_n, Y_n) up to the stop, and whether the motion stops."""
    mu_s = mu_k if mu_s is None else mu_s
    w = math.sqrt(1.0 - zeta * zeta)
    half = math.pi / w
    r = math.exp(-zeta * half)
    taus, ys = [0.0], [y0]
    while len(ys) < max_count:
        yn = ys[-1]
        if abs(yn) <= mu_s or yn == 0.0:
            return np.array(taus), np.array(ys), True
        s = math.copysign(1.0, yn)
        ys.append(mu_k * s - (yn - mu_k * s) * r)  # Eq. 16 at ω(τ - τ_n) = π
        taus.append(taus[-1] + half)
    return np.array(taus), np.array(ys), False


def exact_peaks(y0: float, zeta: float, mu: float) -> Peaks:
    """Free turning points of the exact solution as Peaks (the stop point left out)."""
    tn, yn, stops = exact_turning_points(y0, zeta, mu, max_count=400)
    if stops:  # the stop point is where the motion ends, not a free turning point
        tn, yn = tn[:-1], yn[:-1]
    return Peaks(t=tn, value=yn)


def exact_signal(
    tau: np.ndarray, y0: float, zeta: float, mu_k: float, mu_s: float | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Exact dimensionless y(τ), y'(τ) from the initial turning point (y0, 0)."""
    tau = np.asarray(tau, dtype=float)
    w = math.sqrt(1.0 - zeta * zeta)
    beta = zeta / w
    half = math.pi / w
    count = int(tau.max() / half) + 3
    tn, yn, stops = exact_turning_points(y0, zeta, mu_k, mu_s, max_count=count)
    y = np.empty_like(tau)
    yp = np.zeros_like(tau)
    n = np.minimum((tau / half).astype(int), tn.size - 1)
    if stops:
        moving = n < tn.size - 1
    else:
        moving = np.ones(tau.shape, bool)
    Y = yn[n]
    s = np.sign(Y)
    c = mu_k * s
    u = tau - tn[n]
    env = (Y - c) * np.exp(-zeta * u)
    y = np.where(moving, c + env * (np.cos(w * u) + beta * np.sin(w * u)), yn[-1])
    yp = np.where(moving, -env / w * np.sin(w * u), 0.0)
    return y, yp


def _rhs(zeta: float, mu_k: float):
    def f(_t: float, z: np.ndarray) -> list[float]:
        y, v = z
        return [v, -2.0 * zeta * v - y - mu_k * np.sign(v)]

    return f


@pytest.mark.parametrize(
    ("y0", "zeta", "mu_k"), [(10.0, 0.02, 0.03), (3.0, 0.001, 0.1), (10.0, 0.1, 0.0)]
)
def test_exact_signal_matches_ode_integration(y0: float, zeta: float, mu_k: float) -> None:
    # integrate each half-cycle separately (sgn y' is constant inside one), so the
    # discontinuity of the friction force sits at the integration boundaries
    w = math.sqrt(1 - zeta**2)
    half = math.pi / w
    z = np.array([y0, 0.0])
    tn, _, _ = exact_turning_points(y0, zeta, mu_k)
    n_half = min(8, tn.size - 1)
    for k in range(n_half):
        v_sign = -math.copysign(1.0, z[0])
        f = _rhs(zeta, 0.0)

        def g(t, zz, f=f, v_sign=v_sign):
            dy, dv = f(t, zz)
            return [dy, dv - mu_k * v_sign]

        grid = np.linspace(k * half, (k + 1) * half, 41)
        sol = solve_ivp(g, (grid[0], grid[-1]), z, t_eval=grid, rtol=1e-11, atol=1e-12)
        y_ref, yp_ref = exact_signal(grid[:-1], y0, zeta, mu_k)
        # tolerance: the integrator's rtol 1e-11 over 8 half-cycles, times the amplitude
        np.testing.assert_allclose(sol.y[0][:-1], y_ref, atol=1e-8 * y0)
        np.testing.assert_allclose(sol.y[1][:-1], yp_ref, atol=1e-8 * y0)
        z = sol.y[:, -1]


def test_exact_signal_sticks_at_rest_position() -> None:
    tn, yn, stops = exact_turning_points(2.0, 0.01, 0.1)
    assert stops and abs(yn[-1]) <= 0.1
    tau = np.array([tn[-1] + 1.0, tn[-1] + 50.0])
    y, yp = exact_signal(tau, 2.0, 0.01, 0.1)
    assert np.all(y == yn[-1]) and np.all(yp == 0.0)


#: Natural frequency of the paper's rig [Hz] and the default sample rate [Hz].
F_HZ = 32.6
FS_HZ = 2000.0


def sampled(
    zeta: float,
    mu_k: float,
    y0: float,
    *,
    fs: float = FS_HZ,
    duration: float | None = None,
    noise_x: float = 0.0,
    noise_v: float = 0.0,
    offset: float = 0.0,
    lead: float = 0.0,
    seed: int = 0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A sampled recording t [s], x, v with ℓ = 1 and Ω = 2π·32.6 Hz.

    ``duration`` [s] defaults to the stop plus 20 % (or 12/ζ time constants
    without friction, capped at 400π/Ω); ``lead`` [s] of rest before the release.
    """
    omega = 2 * math.pi * F_HZ
    tn, _, stops = exact_turning_points(y0, zeta, mu_k)
    if duration is None:
        if stops:
            tau_end = tn[-1] * 1.2 + 20.0
        else:
            tau_end = min(400 * math.pi, 12.0 / zeta)
        duration = tau_end / omega
    t = np.arange(0.0, duration + lead, 1.0 / fs)
    tau = np.maximum(t - lead, 0.0) * omega
    y, yp = exact_signal(tau, y0, zeta, mu_k)
    rng = np.random.default_rng(seed)
    x = y + offset + noise_x * rng.standard_normal(t.size)
    v = yp * omega + noise_v * rng.standard_normal(t.size)
    return t, x, v
