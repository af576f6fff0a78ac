"""The independent solver of any law's motion (``solve_ivp``), against closed forms,
the exact simulator and the fit's own half-cycle integrator."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bayestribo.model.laws import get_law
from bayestribo.synthetic import DissipationLaw, LawParameters, Release, Sensor, simulate
from bayestribo.synthetic.motion import integrate_law


def test_coulomb_turning_points_fall_by_twice_the_friction_every_half_period() -> None:
    # Y_n = (-1)^n (y0 - 2nμ) at τ_n = nπ; the pin sticks at the first |Y_n| <= ρμ
    # (Rigaud et al. 2010, Eq. 8, 20 with ζ = 0)
    y0, mu, ratio = 3.05, 0.2, 1.5
    motion = integrate_law(get_law("coulomb"), {"mu_k": mu, "mu_s_ratio": ratio}, y0)
    n = np.arange(motion.turning_points.size)
    np.testing.assert_allclose(motion.turning_times, n * math.pi, rtol=0, atol=1e-8)
    np.testing.assert_allclose(motion.turning_points, (-1.0) ** n * (y0 - 2 * n * mu), atol=1e-9)
    assert motion.stopped and abs(motion.turning_points[-1]) <= ratio * mu
    assert abs(motion.turning_points[-2]) > ratio * mu


def test_viscous_motion_is_the_damped_oscillator() -> None:
    # y = y0 e^{-ζτ} (cos ω_d τ + (ζ/ω_d) sin ω_d τ), ω_d = √(1 - ζ²)
    y0, zeta = 2.0, 0.03
    motion = integrate_law(get_law("viscous"), {"zeta": zeta}, y0, tau_limit=40.0)
    tau = np.linspace(0.0, 40.0, 801)
    y, yp = motion.sample(tau)
    wd = math.sqrt(1.0 - zeta**2)
    decay = y0 * np.exp(-zeta * tau)
    exact = decay * (np.cos(wd * tau) + zeta / wd * np.sin(wd * tau))
    exact_p = -decay * np.sin(wd * tau) / wd
    np.testing.assert_allclose(y, exact, rtol=0, atol=1e-9 * y0)
    np.testing.assert_allclose(yp, exact_p, rtol=0, atol=1e-9 * y0)
    assert not motion.stopped


def test_quadratic_drag_loses_its_harmonic_dissipation_per_half_cycle() -> None:
    # At small damping a half cycle of swing A = (a_s + a_e)/2 loses (4/3)γA³ (half of
    # ∮γ|y'|³dτ over y = A cos τ), so a_s - a_e = (4/3)γA², to second order in γA
    gamma, y0 = 1e-3, 5.0
    motion = integrate_law(get_law("quadratic"), {"c2": gamma}, y0, tau_limit=40.0)
    a = np.abs(motion.turning_points)
    swing = 0.5 * (a[:-1] + a[1:])
    drop = a[:-1] - a[1:]
    np.testing.assert_allclose(drop, (4.0 / 3.0) * gamma * swing**2, rtol=(gamma * y0) ** 2)


LAWS = {
    "viscous+quadratic": ({"zeta": 0.01, "c2": 0.005}, 7.0),
    "coulomb+power": ({"mu_k": 0.02, "mu_s_ratio": 1.5, "zeta_alpha": 0.01, "alpha": 1.5}, 9.0),
    "coulomb+hysteretic": ({"mu_k": 0.05, "mu_s_ratio": 1.5, "eta": 0.01}, 9.0),
    "viscous+coulomb+quadratic": (
        {"zeta": 0.005, "mu_k": 0.04, "mu_s_ratio": 1.2, "c2": 0.01},
        6.0,
    ),
}


@pytest.mark.parametrize("name", list(LAWS))
def test_the_solver_agrees_with_the_fits_integrator(name: str) -> None:
    values, y0 = LAWS[name]
    law = get_law(name)
    motion = integrate_law(law, values, y0, tau_limit=120.0)
    n = motion.turning_times.size
    tau_n, y_n = law.turning_points(values, y0, tau_max=motion.turning_times[-1] + 1e-6)
    assert tau_n.size >= n
    # two integrations of the same law by different methods: 1e-9 of y0 measured
    np.testing.assert_allclose(motion.turning_times, tau_n[:n], rtol=0, atol=1e-7)
    np.testing.assert_allclose(motion.turning_points, y_n[:n], rtol=0, atol=1e-8 * y0)
    if motion.stopped:
        assert tau_n.size == n  # the pin sticks at the same turning point


def test_a_law_of_the_registry_simulates_as_the_exact_simulator() -> None:
    """viscous+coulomb by solve_ivp (with the magnet's fade) against the exact
    piecewise solution of the package's own simulator, on the same grid."""
    quiet = Sensor(displacement_noise_m=0.0, velocity_noise_m_per_s=0.0, sample_rate_Hz=5000.0)
    release = Release(initial_displacement_m=2e-3)
    exact = simulate(DissipationLaw(0.01, 0.02, 0.03), release=release, sensor=quiet, seed=1)
    law = LawParameters("viscous+coulomb", {"zeta": 0.01, "mu_k": 0.02, "mu_s_ratio": 1.5})
    ode = simulate(law, release=release, sensor=quiet, seed=1)
    assert ode.n_samples == exact.n_samples
    np.testing.assert_array_equal(ode.time, exact.time)
    np.testing.assert_allclose(ode.displacement, exact.displacement, rtol=0, atol=2e-12)
    # within 1e-9 of x0 and of the peak speed (0.41 m/s): 2e-10 measured
    np.testing.assert_allclose(ode.velocity, exact.velocity, rtol=0, atol=4e-10)
    stop = exact.metadata["simulation"]["motion_duration_s"]
    assert ode.metadata["simulation"]["motion_duration_s"] == pytest.approx(stop, abs=1e-9)


@pytest.mark.parametrize(
    ("name", "values", "y0", "limit", "match"),
    [
        ("coulomb", {"mu_k": 1.0, "mu_s_ratio": 2.0}, 1.5, math.inf, "would not move"),
        ("viscous", {"zeta": 1.0}, 1.0, 50.0, "overdamped"),
        ("viscous", {"zeta": 0.01}, 1.0, math.inf, "never stops"),
        ("coulomb+hysteretic", {"mu_k": 0.0, "eta": -0.1}, 1.0, math.inf, "expected a finite"),
    ],
)
def test_motions_outside_a_laws_domain_are_refused(name, values, y0, limit, match) -> None:
    law = get_law(name)
    values = {"mu_s_ratio": 1.0, **values} if "coulomb" in name else values
    with pytest.raises(ValueError, match=match):
        integrate_law(law, values, y0, tau_limit=limit)
