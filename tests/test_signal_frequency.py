"""The frequency measured from zero crossings, against an independent ODE solution."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bayestribo.signal.frequency import (
    crossing_frequency,
    frequency_trend,
    oscillation_frequency,
    turning_point_trend,
)

F_HZ, ZETA, XC = 32.6, 0.0236, 6.2e-6  # natural frequency, damping, Coulomb offset [m]


def _decay(
    rate_hz: float, rest_s: float = 0.3, k3_over_k: float = 0.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """x, v of m x'' + c x' + k (x + k3_over_k x³) + F sign(x') = 0 by solve_ivp, half
    cycle by half cycle (the friction sign is constant between velocity zeros), then at
    rest."""
    w = 2 * np.pi * F_HZ
    t_all, x_all, v_all = [], [], []
    t0, y = 0.0, np.array([2e-3, 0.0])
    direction = -1.0
    while abs(y[0]) > XC:  # a turning point outside ±x_c: the pin moves on

        def rhs(t, s, d=direction):
            spring = s[0] + k3_over_k * s[0] ** 3
            return [s[1], -2 * ZETA * w * s[1] - w * w * (spring + d * XC)]

        def stop(t, s, d=direction):
            return s[1] if t > 0 else d

        stop.terminal, stop.direction = True, -direction
        sol = solve_ivp(
            rhs, (t0, t0 + 1.0), y, events=stop, rtol=1e-11, atol=1e-14, dense_output=True
        )
        t1 = sol.t_events[0][0]
        grid = np.arange(np.ceil(t0 * rate_hz), np.floor(t1 * rate_hz) + 1) / rate_hz
        grid = grid[(grid >= t0) & (grid < t1)]
        states = sol.sol(grid)
        t_all.append(grid), x_all.append(states[0]), v_all.append(states[1])
        t0, y = t1, sol.y_events[0][0]
        direction = -direction
    rest = np.arange(np.ceil(t0 * rate_hz), np.floor((t0 + rest_s) * rate_hz)) / rate_hz
    t_all.append(rest), x_all.append(np.full(rest.size, y[0])), v_all.append(0.0 * rest)
    return np.concatenate(t_all), np.concatenate(x_all), np.concatenate(v_all)


DAMPED_HZ = F_HZ * np.sqrt(1 - ZETA**2)


@pytest.mark.parametrize("rate_hz", [2_000.0, 10_000.0, 50_000.0])
def test_velocity_crossings_give_the_damped_frequency(rate_hz):
    t, x, v = _decay(rate_hz)
    rng = np.random.default_rng(1)
    noisy_v = v + rng.normal(0.0, 1.5e-5, v.size)  # 1000 × the vibrometer resolution
    # Linear interpolation between samples errs by O((ω dt)²) per crossing at worst.
    assert oscillation_frequency(t, x, noisy_v) == pytest.approx(DAMPED_HZ, rel=2e-5)


def test_displacement_alone_is_differentiated_not_crossed():
    t, x, _ = _decay(10_000.0)
    noisy = x + np.random.default_rng(2).normal(0.0, 1.5e-7, x.size)
    assert oscillation_frequency(t, noisy, None) == pytest.approx(DAMPED_HZ, rel=2e-4)
    # The displacement's own crossings drift with the Coulomb offset: the reason the
    # velocity (or the derivative) is used.
    assert abs(crossing_frequency(t, x) / DAMPED_HZ - 1) > 5e-4


def test_no_oscillation_gives_none():
    t = np.arange(1000) / 1e4
    assert crossing_frequency(t, np.zeros_like(t)) is None
    assert oscillation_frequency(t, np.exp(-t), None) is None


def test_a_linear_oscillator_has_no_frequency_trend():
    t, x, v = _decay(10_000.0)
    rng = np.random.default_rng(3)
    trend = frequency_trend(t, x + rng.normal(0, 1.5e-6, x.size), v + rng.normal(0, 1.5e-7, v.size))
    # Viscous damping and Coulomb friction keep the half period: a change far below
    # the 2e-4 the fit reports, and no significant slope.
    assert abs(trend.change) < 5e-5 and abs(trend.z) < 4


def test_a_cubic_spring_shows_as_a_half_period_changing_with_amplitude():
    # k3/k = 667 m^-2 raises the frequency at 2 mm by 0.1 % (Duffing, 3/8 k3/k A²).
    t, x, v = _decay(10_000.0, k3_over_k=667.0)
    rng = np.random.default_rng(4)
    trend = frequency_trend(t, x + rng.normal(0, 1.5e-6, x.size), v + rng.normal(0, 1.5e-7, v.size))
    # Large swings are faster: the half period grows as the swing decays, by about
    # 3/8 k3/k (A_max² - A_min²) ~ 0.1 % over the analysed swings (the first one is
    # left out, so somewhat less).
    assert 4e-4 < trend.change < 1.2e-3 and trend.z > 8


@pytest.mark.parametrize("fs", [10_000.0, 100_000.0])
def test_an_anti_alias_filter_makes_no_frequency_trend(fs):
    """A linear oscillator through a 4th-order Butterworth filter at 2 kHz, 10x the
    resolution (the independent simulator of ``test_signal_frontend``): the filter
    moves each turning time by about x_c/|Y_n| times its spread in time, which the
    half periods once read as a trend (-1.1e-5 at z = -1.6 at 10 kHz, -7e-6 at z = -6.7
    at 100 kHz); the decay's turning times and the b/|Y| terms leave none."""
    from test_signal_frontend import RIG, add_effects, record

    from bayestribo.signal.decay import energy_decay

    t, x, v, _, _ = record(fs, 0.1, 0.1)
    zs = []
    for seed in range(8):
        xs, vs = add_effects(t, x, v, fs, seed=seed, filt=True)
        decay = energy_decay(t, xs, vs, rig=RIG)
        trend = turning_point_trend(decay.turning_times, decay.peaks.value)
        raw = frequency_trend(t, xs, vs)
        assert abs(trend.change) < 1e-6 and abs(raw.change) < 3e-6
        zs.append(trend.z)
    # noise-sized: no |z| beyond 3.5 in 8 runs, no mean beyond 2 standard errors
    # (at 100 kHz the mean is -1.5: a residual of 5e-8 in the change)
    assert np.max(np.abs(zs)) < 3.5
    assert abs(np.mean(zs)) < 2.0


def test_the_decay_turning_times_show_a_cubic_spring():
    t, x, v = _decay(10_000.0, k3_over_k=667.0)
    rng = np.random.default_rng(4)
    xs, vs = x + rng.normal(0, 1.5e-6, x.size), v + rng.normal(0, 1.5e-7, v.size)
    from bayestribo.signal.decay import energy_decay

    decay = energy_decay(t, xs, vs)
    trend = turning_point_trend(decay.turning_times, decay.peaks.value)
    assert 4e-4 < trend.change < 1.2e-3 and trend.z > 8


def test_turning_point_trend_needs_eight_turning_points():
    assert turning_point_trend(np.arange(7.0), (-1.0) ** np.arange(7)) is None
    with pytest.raises(ValueError, match="differ in length"):
        turning_point_trend(np.arange(9.0), np.ones(8))
