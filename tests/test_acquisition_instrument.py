"""Simulated instrument: the decay it streams against an independent ODE integration."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bayestribo.acquisition.instrument import SimulationConfig


def integrate_decay(y0: float, zeta: float, mu_k: float, tau: np.ndarray, half_cycles: int):
    """y'' + 2ζy' + y = -μ_k sgn(y') (Rigaud et al. 2010, Eq. 12), half-cycle by half-cycle.

    Each half-cycle starts at rest at a turning point Y and moves towards the origin,
    so sgn(y') = -sgn(Y) until the next turning point (event y' = 0).
    """
    y = np.full_like(tau, np.nan)
    yp = np.full_like(tau, np.nan)
    start, state = 0.0, np.array([y0, 0.0])
    for _ in range(half_cycles):
        sign = -np.sign(state[0])

        def rhs(t, s, sign=sign):
            return [s[1], -2 * zeta * s[1] - s[0] - mu_k * sign]

        def turn(t, s):
            return s[1]

        turn.terminal, turn.direction = True, -sign
        sol = solve_ivp(
            rhs,
            (start, start + 10),
            state,
            events=turn,
            rtol=1e-11,
            atol=1e-13,
            dense_output=True,
            first_step=1e-6,
        )
        end = sol.t_events[0][0]
        inside = (tau >= start) & (tau <= end)
        y[inside], yp[inside] = sol.sol(tau[inside])
        start, state = end, sol.y_events[0][0]
    return y, yp, start


def test_simulated_decay_matches_the_equation_of_motion():
    cfg = SimulationConfig(sample_rate_Hz=5000.0, duration_s=0.2, x0_m=5e-4)
    counts = cfg.decay_counts()
    omega = 2 * math.pi * cfg.natural_frequency_Hz
    ell = cfg.load_N / (cfg.mass_kg * omega**2)
    tau = np.arange(len(counts)) / cfg.sample_rate_Hz * omega
    y, yp, end = integrate_decay(cfg.x0_m / ell, cfg.zeta, cfg.mu_k, tau, half_cycles=6)
    covered = tau <= end
    assert covered.sum() >= 450  # six half-cycles: 3 periods of 30.7 ms at 5 kS/s = 460
    header = cfg.header
    x_counts = y[covered] * ell / header.displacement_scale_m
    v_counts = yp[covered] * ell * omega / header.velocity_scale_m_per_s
    # Rounding to counts moves a sample by at most half a count; the ODE tolerance
    # (rtol 1e-11) adds far less than 0.01 count on a signal of ~8000 counts.
    assert np.max(np.abs(counts[covered, 0] - x_counts)) <= 0.51
    assert np.max(np.abs(counts[covered, 1] - v_counts)) <= 0.51
    # And the quantised decay is not trivially flat: it spans most of its range.
    assert counts[:, 0].max() - counts[:, 0].min() > 10_000


def test_rest_position_before_release():
    cfg = SimulationConfig()
    assert cfg.rest_counts()[0] == round(cfg.x0_m / cfg.header.displacement_scale_m)
    assert cfg.rest_counts()[1] == 0


def test_settings_that_would_clip_are_refused():
    with pytest.raises(ValueError, match="clipped"):
        SimulationConfig(x0_m=3e-3, displacement_range_m=2e-3)
    with pytest.raises(ValueError, match="velocity_range_m_per_s"):
        SimulationConfig(velocity_range_m_per_s=0.01).decay_counts()
    with pytest.raises(ValueError, match="sample_rate_Hz"):
        SimulationConfig(sample_rate_Hz=0.0)


def test_noise_is_seeded():
    a = SimulationConfig(duration_s=0.05, noise_counts=3.0, seed=4).decay_counts()
    b = SimulationConfig(duration_s=0.05, noise_counts=3.0, seed=4).decay_counts()
    c = SimulationConfig(duration_s=0.05, noise_counts=3.0, seed=5).decay_counts()
    assert np.array_equal(a, b) and not np.array_equal(a, c)
