"""The averaged model (Eq. 32-41) against quadrature, its limits and the exact model."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad, solve_ivp

from bayestribo.model import (
    averaged_amplitude,
    averaged_energy,
    averaged_pi,
    exact_pi,
    extinction_time,
    stop_time,
)

REGULAR = [(0.0236, 0.0294, 9.5), (0.05, 0.02, 15.0), (0.005, 0.01, 5.0), (0.1, 0.3, 2.0)]


@pytest.mark.parametrize(("zeta", "mu_k", "y0"), REGULAR)
def test_amplitude_solves_the_averaged_equation(zeta, mu_k, y0):
    # Eq. 32, a' = -ζa - 2μ_k/π, integrated numerically up to just before T_f.
    tf = float(extinction_time(y0, zeta, mu_k))
    tau = np.linspace(0.0, 0.99 * tf, 50)
    sol = solve_ivp(
        lambda _t, a: -zeta * a - 2 * mu_k / np.pi,
        (0, tau[-1]),
        [y0],
        t_eval=tau,
        rtol=1e-12,
        atol=1e-12,
    )
    np.testing.assert_allclose(averaged_amplitude(tau, y0, zeta, mu_k), sol.y[0], atol=1e-9)
    assert float(averaged_amplitude(tf, y0, zeta, mu_k)) == pytest.approx(0.0, abs=1e-12)
    assert float(averaged_amplitude(tf + 5.0, y0, zeta, mu_k)) == 0.0


@pytest.mark.parametrize(("zeta", "mu_k", "y0"), REGULAR)
def test_pi_matches_quadrature_of_energy(zeta, mu_k, y0):
    tf = float(extinction_time(y0, zeta, mu_k))
    tau = np.linspace(0.0, tf, 7)
    ref = [
        quad(lambda u: float(averaged_energy(u, y0, zeta, mu_k)), t, tf, epsabs=0, epsrel=1e-12)[0]
        for t in tau
    ]
    np.testing.assert_allclose(averaged_pi(tau, y0, zeta, mu_k), ref, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize(("zeta", "mu_k", "y0"), REGULAR)
def test_eq40_with_corrected_constant(zeta, mu_k, y0):
    gamma = 2 * mu_k / (np.pi * zeta)  # Eq. 36
    lam = y0 + gamma
    tau = np.linspace(0.0, float(extinction_time(y0, zeta, mu_k)), 5)

    def eq40(constant: float) -> np.ndarray:
        return (
            lam**2 / (4 * zeta) * np.exp(-2 * zeta * tau)
            - lam * gamma / zeta * np.exp(-zeta * tau)
            - gamma**2 / 2 * tau
            + constant
        )

    corrected = gamma**2 / zeta * (0.75 - 0.5 * np.log(gamma / lam))
    printed = gamma**2 / zeta * (0.75 - np.log(gamma / lam))  # Eq. 41 as printed
    np.testing.assert_allclose(
        averaged_pi(tau, y0, zeta, mu_k), eq40(corrected), rtol=1e-9, atol=1e-9 * eq40(corrected)[0]
    )
    # The printed constant leaves Π_app(T_f) = -(Γ²/2ζ) ln(Γ/Λ) > 0 instead of 0.
    assert eq40(printed)[-1] == pytest.approx(-(gamma**2) / (2 * zeta) * np.log(gamma / lam))
    assert eq40(printed)[-1] > 1e-3 * eq40(corrected)[0]


def test_extinction_time_eq38():
    zeta, mu_k, y0 = 0.0236, 0.0294, 9.5
    gamma = 2 * mu_k / (np.pi * zeta)
    assert float(extinction_time(y0, zeta, mu_k)) == pytest.approx(
        -np.log(gamma / (y0 + gamma)) / zeta, rel=1e-13
    )


def test_pure_coulomb_limit():
    # ζ = 0: a = a0 - 2μ_kτ/π, T_f = πa0/(2μ_k), Π(0) = ∫ a²/2 dτ = πa0³/(12μ_k).
    mu_k, y0 = 0.03, 6.0
    tau = np.linspace(0.0, 100.0, 11)
    np.testing.assert_allclose(
        averaged_amplitude(tau, y0, 0.0, mu_k),
        np.maximum(y0 - 2 * mu_k * tau / np.pi, 0),
        rtol=1e-14,
    )
    assert float(extinction_time(y0, 0.0, mu_k)) == pytest.approx(np.pi * y0 / (2 * mu_k))
    assert float(averaged_pi(0.0, y0, 0.0, mu_k)) == pytest.approx(np.pi * y0**3 / (12 * mu_k))
    # Continuity: a vanishing ζ gives the limit, without 0/0 or overflow.
    for z in (1e-300, 1e-12, 1e-8):
        assert float(averaged_pi(0.0, y0, z, mu_k)) == pytest.approx(
            np.pi * y0**3 / (12 * mu_k), rel=10 * z * y0 / mu_k + 1e-13
        )


def test_pure_viscous_limit():
    zeta, y0 = 0.0033, 2.0
    tau = np.linspace(0.0, 1000.0, 11)
    np.testing.assert_allclose(averaged_amplitude(tau, y0, zeta, 0.0), y0 * np.exp(-zeta * tau))
    assert np.isinf(extinction_time(y0, zeta, 0.0))
    np.testing.assert_allclose(
        averaged_pi(tau, y0, zeta, 0.0), (y0 * np.exp(-zeta * tau)) ** 2 / (4 * zeta), rtol=1e-13
    )
    for mk in (1e-300, 1e-15, 1e-10):
        assert float(averaged_pi(0.0, y0, zeta, mk)) == pytest.approx(y0**2 / (4 * zeta), rel=1e-6)
    assert np.isinf(averaged_pi(0.0, y0, 0.0, 0.0))


@settings(max_examples=300, deadline=None)
@given(
    # Exact zeros and values down to 1e-10; below that Π itself (∝ 1/μ_k or 1/ζ)
    # exceeds the double range for some amplitudes and inf is the right answer.
    zeta=st.one_of(st.just(0.0), st.floats(1e-10, 0.99)),
    mu_k=st.one_of(st.just(0.0), st.floats(1e-10, 10.0)),
    y0=st.floats(0.0, 1e3),
    tau=st.floats(0.0, 1e6),
)
def test_finite_and_monotonic_everywhere(zeta, mu_k, y0, tau):
    if zeta == 0.0 and mu_k == 0.0:
        return
    pi0 = averaged_pi(0.0, y0, zeta, mu_k)
    pi = averaged_pi(tau, y0, zeta, mu_k)
    assert np.isfinite(pi0) and np.isfinite(pi)
    assert 0.0 <= pi <= pi0 * (1 + 1e-12)


@pytest.mark.parametrize(
    ("zeta", "mu_k", "y0"),
    [
        (0.0236, 0.0294, 9.5),
        (0.05, 0.02, 15.0),
        (0.005, 0.01, 5.0),
        (0.001, 0.05, 10.0),
        (0.02, 0.0, 5.0),
    ],
)
def test_averaged_agrees_with_exact_in_its_regime(zeta, mu_k, y0):
    """Averaging is an expansion in the small dissipation per cycle.

    For pure viscous damping the exact Π(0) is ½y0²[(1+β²)/(2ζ) + ζ(1-β²)/2] against
    y0²/(4ζ) averaged: a relative difference of about 2ζ². Friction adds a term
    proportional to μ_k/y0 (the centre of the oscillation jumps by 2μ_k each half cycle),
    measured below 0.015 μ_k/y0. The tolerance 3ζ² + 0.05 μ_k/y0 (relative to Π(0))
    covers both with margin and still fails for a wrong ζ or μ_k by a few per cent.
    """
    mu_s = 1.2 * mu_k
    end = min(float(stop_time(y0, zeta, mu_k, mu_s)), 400.0)
    tau = np.linspace(0.0, 0.9 * end, 40)
    exact = exact_pi(tau, y0, zeta, mu_k, mu_s)
    approx = averaged_pi(tau, y0, zeta, mu_k)
    tol = 3 * zeta**2 + 0.05 * mu_k / y0
    np.testing.assert_allclose(approx, exact, rtol=0, atol=tol * exact[0])
    # A 3 % error in ζ or μ_k is far outside that tolerance (the test can fail).
    assert np.max(np.abs(averaged_pi(tau, y0, 1.03 * zeta, 1.03 * mu_k) - exact)) > tol * exact[0]
    if mu_k > 0:
        # T_f ignores the stick band and the half-cycle granularity: within one period.
        assert abs(float(extinction_time(y0, zeta, mu_k)) - end) < 2 * np.pi


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"zeta": -1e-3}, "zeta"),
        ({"zeta": 1.0}, "zeta"),
        ({"mu_k": -1.0}, "mu_k"),
        ({"y0": -1.0}, "y0"),
        ({"tau": np.nan}, "tau"),
        ({"tau": -2.0}, "tau"),
        # one bad value among good ones, and the non-finite ones of each argument
        ({"tau": [0.0, 1.0, np.inf]}, "tau"),
        ({"tau": "later"}, "tau"),
        ({"zeta": [0.02, np.nan]}, "zeta"),
        ({"mu_k": np.inf}, "mu_k"),
        ({"y0": [5.0, -np.inf]}, "y0"),
        ({"tau_end": -1.0}, "tau_end"),
        ({"tau_end": np.nan}, "tau_end"),
    ],
)
def test_bad_arguments(kwargs, name):
    args = {"tau": 1.0, "y0": 5.0, "zeta": 0.02, "mu_k": 0.03}
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        averaged_pi(**args)
