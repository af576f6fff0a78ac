"""The exact piecewise model against independent computations.

References: ``solve_ivp`` integrated half cycle by half cycle with velocity-zero
events (bayestribo.model.reference, no shared code), adaptive quadrature of E, and the
classical closed-form limits (pure Coulomb: peaks fall by 2μ_k per half cycle;
pure viscous: one damped cosine for all time).
"""

from __future__ import annotations

from itertools import pairwise

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from bayestribo.model import (
    exact_energy,
    exact_pi,
    exact_response,
    rest_position,
    stop_time,
    turning_points,
)
from bayestribo.model._chunks import BLOCK
from bayestribo.model.reference import ode_pi, ode_solve

# (zeta, mu_k, mu_s, y0, yp0): the paper's Fig. 3 case, the rig's regime, limits, and
# starts inside a half cycle (both signs of velocity, both sides of the centre).
CASES = [
    pytest.param(0.05, 0.02, 0.03, 15.0, 0.0, id="fig3"),
    pytest.param(0.0236, 0.0294, 0.035, 9.5, 0.0, id="glycerol"),
    pytest.param(0.0, 0.05, 0.06, 6.0, 0.0, id="coulomb-only"),
    pytest.param(1e-7, 0.02, 0.03, 2.0, 0.0, id="tiny-zeta"),
    pytest.param(0.3, 0.1, 0.25, -4.0, 0.0, id="strong-damping-negative-start"),
    pytest.param(0.03, 0.05, 0.08, 4.0, -2.5, id="moving-start-towards-centre"),
    pytest.param(0.2, 0.1, 0.1, -5.0, 3.0, id="moving-start-negative"),
    pytest.param(0.02, 0.04, 0.04, 1.0, 2.0, id="moving-start-away-from-centre"),
]


@pytest.mark.parametrize(("zeta", "mu_k", "mu_s", "y0", "yp0"), CASES)
def test_response_matches_ode_integration(zeta, mu_k, mu_s, y0, yp0):
    sol = ode_solve(y0, zeta, mu_k, mu_s, yp0)
    tau = np.linspace(0.0, 1.1 * sol.stop_time, 801)  # includes the rest after the stop
    y, yp = exact_response(tau, y0, zeta, mu_k, mu_s, yp0)
    y_ref, yp_ref = sol.response(tau)
    # The ODE is solved to rtol 1e-12 per half cycle; agreement to 1e-8 of the
    # initial amplitude is the requirement.
    scale = max(abs(y0), abs(yp0))
    np.testing.assert_allclose(y, y_ref, rtol=0, atol=1e-8 * scale)
    np.testing.assert_allclose(yp, yp_ref, rtol=0, atol=1e-8 * scale)


@pytest.mark.parametrize(("zeta", "mu_k", "mu_s", "y0", "yp0"), CASES)
def test_turning_points_and_stop_match_ode(zeta, mu_k, mu_s, y0, yp0):
    sol = ode_solve(y0, zeta, mu_k, mu_s, yp0)
    tau_n, y_n = turning_points(y0, zeta, mu_k, mu_s, yp0)
    assert len(tau_n) == len(sol.turning_times)
    np.testing.assert_allclose(tau_n, sol.turning_times, rtol=0, atol=1e-8)
    np.testing.assert_allclose(y_n, sol.turning_positions, rtol=0, atol=1e-8 * abs(y0))
    assert stop_time(y0, zeta, mu_k, mu_s, yp0) == pytest.approx(sol.stop_time, abs=1e-8)
    assert rest_position(y0, zeta, mu_k, mu_s, yp0) == pytest.approx(
        sol.rest_position, abs=1e-8 * abs(y0)
    )
    assert abs(y_n[-1]) <= mu_s  # sticks inside ±μ_s (Eq. 8) ...
    assert np.all(np.abs(y_n[:-1][tau_n[:-1] > 0]) > mu_s)  # ... and not before


@pytest.mark.parametrize("backend", ["compiled", "numpy"])
@pytest.mark.parametrize(("zeta", "mu_k", "mu_s", "y0", "yp0"), CASES)
def test_pi_matches_quadrature_of_ode_energy(zeta, mu_k, mu_s, y0, yp0, backend):
    sol = ode_solve(y0, zeta, mu_k, mu_s, yp0)
    tau = np.linspace(0.0, sol.stop_time, 9)[:-1]
    pi = exact_pi(tau, y0, zeta, mu_k, mu_s, yp0, backend=backend)
    ref = ode_pi(sol, tau)
    # Quadrature to rtol 1e-12 per half cycle on an ODE solution good to ~1e-10.
    np.testing.assert_allclose(pi, ref, rtol=0, atol=1e-8 * ref[0])
    assert exact_pi(sol.stop_time + 1.0, y0, zeta, mu_k, mu_s, yp0, backend=backend) == 0.0


@pytest.mark.parametrize("backend", ["compiled", "numpy"])
@pytest.mark.parametrize(("zeta", "mu_k", "mu_s", "y0", "yp0"), CASES[:5])
def test_truncated_pi_is_difference_of_untruncated(zeta, mu_k, mu_s, y0, yp0, backend):
    end = stop_time(y0, zeta, mu_k, mu_s, yp0)
    tau = np.linspace(0.0, end, 50)
    for tau_end in (0.37 * end, 0.5 * end + 0.1, 2.0 * end):
        truncated = exact_pi(tau, y0, zeta, mu_k, mu_s, yp0, tau_end=tau_end, backend=backend)
        full = exact_pi(tau, y0, zeta, mu_k, mu_s, yp0, backend=backend)
        full_end = exact_pi(min(tau_end, end), y0, zeta, mu_k, mu_s, yp0, backend=backend)
        expected = np.where(tau < tau_end, full - full_end, 0.0)
        np.testing.assert_allclose(truncated, expected, rtol=1e-10, atol=1e-10 * full[0])


def test_truncated_pi_against_quadrature_inside_a_half_cycle():
    zeta, mu_k, mu_s, y0 = 0.0236, 0.0294, 0.035, 9.5
    tau_end = 123.4567
    tau = np.array([0.0, 3.3, 60.0, 110.0])
    pi = exact_pi(tau, y0, zeta, mu_k, mu_s, tau_end=tau_end)
    tau_n, _ = turning_points(y0, zeta, mu_k, mu_s)
    end = min(tau_end, tau_n[-1])  # the energy of the pin at rest is not counted

    def energy(u: float) -> float:
        return float(exact_energy(u, y0, zeta, mu_k, mu_s))

    ref = []
    for t in tau:
        # Integrate half cycle by half cycle: E is smooth between turning points.
        edges = np.concatenate([[t], tau_n[(tau_n > t) & (tau_n < end)], [end]])
        pieces = [quad(energy, a, b, epsabs=0, epsrel=1e-12)[0] for a, b in pairwise(edges)]
        ref.append(sum(pieces) if t < end else 0.0)
    np.testing.assert_allclose(pi, ref, rtol=1e-9)


def test_pure_coulomb_peaks_fall_linearly():
    # With ζ = 0 successive peak magnitudes drop by exactly 2μ_k (Lorenz 1924).
    _, y_n = turning_points(6.0, 0.0, 0.05, 0.06)
    moving = np.abs(y_n[:-1])
    np.testing.assert_allclose(-np.diff(moving), 0.1, rtol=0, atol=1e-12)
    assert np.all(np.sign(y_n[:-1][1:]) == -np.sign(y_n[:-1][:-1]))


def test_pure_viscous_is_one_damped_cosine_and_pi_converges():
    zeta, y0 = 0.0033, 2.0
    omega = np.sqrt(1 - zeta**2)
    beta = zeta / omega
    tau = np.linspace(0.0, 2000.0, 4001)
    y, _ = exact_response(tau, y0, zeta, 0.0, 0.0)
    expected = y0 * np.exp(-zeta * tau) * (np.cos(omega * tau) + beta * np.sin(omega * tau))
    np.testing.assert_allclose(y, expected, rtol=0, atol=1e-12 * y0)
    assert np.isinf(stop_time(y0, zeta, 0.0, 0.0))

    def energy(u: float) -> float:
        e = np.exp(-zeta * u)
        return 0.5 * (
            (y0 * e * (np.cos(omega * u) + beta * np.sin(omega * u))) ** 2
            + (y0 / omega * e * np.sin(omega * u)) ** 2
        )

    # ∫_0^∞ E by quadrature over each half cycle up to 25 e-folding times of the
    # energy (the remainder is below e^-50 of the total).
    edges = np.arange(0.0, 12.5 / zeta, np.pi / omega)
    ref = sum(quad(energy, a, b, epsabs=0, epsrel=1e-13)[0] for a, b in pairwise(edges))
    assert exact_pi(0.0, y0, zeta, 0.0, 0.0) == pytest.approx(ref, rel=1e-10)
    # and the Laplace transform of E by hand: ½y0²[(1+β²)/(2ζ) + ζ(1-β²)/2].
    laplace = 0.5 * y0**2 * ((1 + beta**2) / (2 * zeta) + 0.5 * zeta * (1 - beta**2))
    assert exact_pi(0.0, y0, zeta, 0.0, 0.0) == pytest.approx(laplace, rel=1e-12)
    assert np.isinf(exact_pi(0.0, y0, 0.0, 0.0, 0.0))
    assert exact_pi(0.0, y0, 0.0, 0.0, 0.0, tau_end=10 * np.pi) == pytest.approx(
        0.5 * y0**2 * 10 * np.pi, rel=1e-12
    )


def test_start_inside_stick_band_never_moves():
    y, yp = exact_response(np.linspace(0, 50, 11), 0.02, 0.05, 0.02, 0.03)
    assert np.all(y == 0.02) and np.all(yp == 0.0)
    assert exact_pi(0.0, 0.02, 0.05, 0.02, 0.03) == 0.0
    assert stop_time(0.02, 0.05, 0.02, 0.03) == 0.0


def test_broadcasting_matches_loop_and_blocked_evaluation():
    rng = np.random.default_rng(7)
    walkers = 64
    zeta = rng.uniform(0.0, 0.1, (walkers, 1))
    mu_k = rng.uniform(0.0, 0.05, (walkers, 1))
    mu_s = mu_k * rng.uniform(1.0, 1.5, (walkers, 1))
    y0 = rng.uniform(1.0, 10.0, (walkers, 1))
    tau = np.linspace(0.0, 300.0, 257)
    assert walkers * tau.size > BLOCK  # exercises the blocked path
    pi = exact_pi(tau, y0, zeta, mu_k, mu_s)
    y, yp = exact_response(tau, y0, zeta, mu_k, mu_s)
    assert pi.shape == y.shape == yp.shape == (walkers, tau.size)
    for i in range(0, walkers, 9):
        args = (y0[i, 0], zeta[i, 0], mu_k[i, 0], mu_s[i, 0])
        np.testing.assert_array_equal(pi[i], exact_pi(tau, *args))
        np.testing.assert_array_equal(y[i], exact_response(tau, *args)[0])


@settings(max_examples=200, deadline=None)
@given(
    zeta=st.floats(0.0, 0.95),
    mu_k=st.floats(0.0, 0.5),
    extra=st.floats(0.0, 0.5),
    y0=st.floats(-20.0, 20.0),
    yp0=st.floats(-20.0, 20.0),
)
# an amplitude times 1 - q below the smallest double: once 0/0 in the count of half cycles
@example(zeta=1.19e-98, mu_k=0.0, extra=1.62e-279, y0=1.62e-279, yp0=1.62e-279)
@example(zeta=0.0, mu_k=5e-324, extra=0.0, y0=0.0, yp0=2.0)
def test_energy_never_increases(zeta, mu_k, extra, y0, yp0):
    tau = np.linspace(0.0, 60.0, 3001)
    e = exact_energy(tau, y0, zeta, mu_k, mu_k + extra, yp0)
    # dE/dτ = -2ζy'² - μ_k|y'| <= 0; allow rounding of a few ulps of E(0).
    assert np.all(np.diff(e) <= 1e-12 * max(e[0], 1.0))
    pi = exact_pi(tau, y0, zeta, mu_k, mu_k + extra, yp0, tau_end=60.0)
    assert np.all(np.diff(pi) <= 1e-12 * max(pi[0], 1.0))
    assert np.all(pi >= -1e-12 * max(pi[0], 1.0))


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"zeta": -0.1}, "zeta"),
        ({"zeta": 1.0}, "zeta"),
        ({"mu_k": -0.01}, "mu_k"),
        ({"mu_s": 0.01}, "mu_s"),
        ({"y0": np.nan}, "y0"),
        ({"yp0": np.inf}, "yp0"),
        ({"tau": -1.0}, "tau"),
        ({"tau": [0.0, np.nan]}, "tau"),
    ],
)
@pytest.mark.parametrize("func", [exact_pi, exact_response])
def test_bad_arguments_raise_naming_them(func, kwargs, name):
    args = {"tau": 1.0, "y0": 5.0, "zeta": 0.02, "mu_k": 0.03, "mu_s": 0.04, "yp0": 0.0}
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        func(**args)


def test_turning_points_needs_a_cap_for_endless_motion():
    with pytest.raises(ValueError, match="max_count"):
        turning_points(1.0, 0.01, 0.0, 0.0)
    tau_n, _ = turning_points(1.0, 0.01, 0.0, 0.0, max_count=10)
    assert len(tau_n) == 10
