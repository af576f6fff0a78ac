"""A velocity-only record at 10 samples a period: its displacement integrated as a
damped oscillation with kinks at its turning points, and the increments taken from the
oscillator's own ∫E between samples."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid, simpson

from bayestribo.signal.decay import energy_decay
from bayestribo.signal.increments import pi_data
from bayestribo.signal.integration import (
    integrate_oscillation,
    oscillation_energy,
    oscillation_pole,
    step_rule,
)
from bayestribo.signal.noise import noise_model

F_HZ, ZETA, XC, X0 = 32.6, 0.0236, 6.2e-6, 2e-3
OMEGA = 2 * math.pi * F_HZ
WD = OMEGA * math.sqrt(1 - ZETA**2)


def _motion(t: np.ndarray, release: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """Viscous damping and Coulomb friction (x_c = μ_kN/k), released from X0 at rest
    at ``release`` [s], half cycle by half cycle in closed form, sticking when the
    swing is within 2 x_c."""
    x = np.full(t.size, X0)
    v = np.zeros(t.size)
    t0, amp, direction = release, X0, -1.0
    while abs(amp) > 2 * XC:
        centre = -direction * XC
        m = (t >= t0) & (t < t0 + math.pi / WD)
        s = t[m] - t0
        env = (amp - centre) * np.exp(-ZETA * OMEGA * s)
        x[m] = centre + env * (np.cos(WD * s) + ZETA * OMEGA / WD * np.sin(WD * s))
        v[m] = -env * OMEGA**2 / WD * np.sin(WD * s)
        amp = centre + (amp - centre) * -math.exp(-ZETA * OMEGA * math.pi / WD)
        t0 += math.pi / WD
        direction = -direction
    x[t >= t0] = amp
    return x, v


def test_the_step_rule_is_exact_for_a_damped_oscillation():
    s = complex(-ZETA * OMEGA, WD)
    h = 1.0 / (10 * F_HZ)
    a, b = step_rule(s, h)
    for c in (1.0, 1j, 0.3 - 2j):
        exact = (c * (np.exp(s * h) - 1) / s).real
        assert a * c.real + b * (c * np.exp(s * h)).real == pytest.approx(exact, rel=1e-12)


def test_the_pole_and_the_displacement_of_ten_samples_a_period_are_exact():
    """At 10 samples a period the trapezoids (their gain divided out) leave the
    displacement off by about 1e-3 of the swing; the oscillator's rule, with the pole
    fitted to the velocity, within 1e-9."""
    fs = 10 * F_HZ
    t = np.arange(0, 0.75, 1 / fs)
    x, v = _motion(t)
    moving = np.flatnonzero(v)
    pole = oscillation_pole(t, v)
    assert pole is not None
    assert pole.real == pytest.approx(-ZETA * OMEGA, rel=1e-6)
    assert pole.imag == pytest.approx(WD, rel=1e-9)
    body = slice(moving[0] + 10, moving[-1])
    exact = integrate_oscillation(t, v, pole)
    error = exact - x
    error -= error[body][0]  # the integration constant
    assert np.max(np.abs(error[body])) < 1e-9 * X0
    half = math.pi * F_HZ / fs
    trapezoid = cumulative_trapezoid(v, t, initial=0.0) / (half / math.tan(half))
    old = trapezoid - x
    old -= old[body][0]
    assert np.max(np.abs(old[body])) > 1e-4 * X0


def test_the_oscillators_energy_between_samples_is_exact():
    fs = 10 * F_HZ
    t = np.arange(0, 0.5, 1 / fs)
    x, v = _motion(t)
    pole = oscillation_pole(t, v)
    x_int = integrate_oscillation(t, v, pole)
    x_int += x[60] - x_int[60]  # the constant (the release's step is not a damped arc)
    x2, v2 = oscillation_energy(t, v, x_int, pole)
    fine = 128
    tf = np.arange(0, (t.size - 1) * fine + 1) / (fs * fine)
    xf, vf = _motion(tf)
    for i in (40, 41, 42, 43, 60, 120):
        a, b = i * fine, (i + 1) * fine + 1
        assert x2[i] == pytest.approx(simpson(xf[a:b] ** 2, x=tf[a:b]), rel=1e-7)
        assert v2[i] == pytest.approx(simpson(vf[a:b] ** 2, x=tf[a:b]), rel=1e-7)


def test_a_velocity_only_record_at_ten_samples_a_period_gives_its_increments():
    """The velocity alone at 326 Hz with white noise of 0.15 µm/s: the observed
    increments are the true ones within their noise (Simpson's rule on E at samples
    put them hundreds of standard deviations off)."""
    fs = 10 * F_HZ
    t = np.arange(0, 0.75, 1 / fs)
    _, v = _motion(t)
    rng = np.random.default_rng(4)
    vs = v + 1.5e-7 * rng.standard_normal(t.size)
    decay = energy_decay(t, None, vs)
    assert decay.derived_channel == "displacement"
    assert decay.energy_steps is not None
    assert decay.energy_steps.shape == (decay.tau.size - 1,)
    data = pi_data(decay, noise_model(decay, {}))
    sl = np.searchsorted(t, decay.t)
    sc = decay.scaling
    # the true ∫E over each increment, from the motion on a grid 64 times finer
    fine = 64
    tf = decay.t[0] + np.arange((decay.t.size - 1) * fine + 1) / (fs * fine)
    xf, vf = _motion(tf)
    assert np.all(sl >= 0)
    yf = (xf - 0.0) / sc.length_scale
    ypf = vf / (sc.length_scale * sc.omega)
    ef = 0.5 * (yf * yf + ypf * ypf)
    edges = np.searchsorted(decay.tau, data.tau_grid)
    tauf = sc.omega * (tf - decay.t[0])
    true = np.array(
        [
            simpson(ef[a * fine : b * fine + 1], x=tauf[a * fine : b * fine + 1])
            for a, b in itertools.pairwise(edges)
        ]
    )
    z = (data.increments - true) / np.sqrt(data.variance)
    assert np.mean(z[:-1] ** 2) < 4.0
