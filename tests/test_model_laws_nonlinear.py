"""The laws on a nonlinear restoring force against an independent integration.

Reference: ``scipy.integrate.solve_ivp`` (DOP853, rtol 1e-12) half cycle by half cycle
of ``y'' = -V'(y) - sgn(y')(g(|y'|) + μ)`` with ``C' = ½y'² + V(y)``, each half cycle
ended by the event y' = 0 (the friction's sign is constant within it). The package's
integrator takes classical Runge-Kutta steps of π/40: its error grows as h⁴, measured
on the pendulum below at 1.2e-7 of Π(0) (4.4e-4 with 10 steps, 1.1e-5 with 20), at
1.7e-7 on the turning points and 4e-5 on their times after 44 half cycles (the phase
error adds up), so the tolerances are 1e-6 of Π(0), 1e-6 on the turning points and
1e-4 on their times.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bayestribo.model.laws import get_law
from bayestribo.model.restoring import get_restoring
from bayestribo.model.restoring.base import RestoringKernel
from bayestribo.model.restoring.duffing import duffing
from bayestribo.model.restoring.linear import potential_kernel, spring_kernel

ZETA, C2, MU = 0.01, 0.02, 0.005
VALUES = {"zeta": ZETA, "c2": C2, "mu_k": MU, "mu_s_ratio": 1.0}
TAU_END = 120.0
BETA = 0.13  # the half period 5 % shorter at y = 1 than at small swings

CASES = {
    "pendulum-90": (
        lambda: get_restoring("pendulum").kernel(),
        math.sin,
        lambda y: 2.0 * math.sin(0.5 * y) ** 2,
        math.pi / 2,
    ),
    "duffing": (
        lambda: duffing(BETA).kernel(),
        lambda y: y + BETA * y**3,
        lambda y: 0.5 * y * y + 0.25 * BETA * y**4,
        1.0,
    ),
}


def _reference(spring, potential, y0, tau_max):
    """Turning times, turning points and C(τ) = ∫₀^τ E of the motion from rest at y0."""
    y, t, c = y0, 0.0, 0.0
    times, points, pieces = [0.0], [y0], []
    while t < tau_max and abs(spring(y)) > MU:
        sgn = -1.0 if y > 0 else 1.0

        def rhs(_t, s, sgn=sgn):
            drag = 2 * ZETA * abs(s[1]) + C2 * s[1] * s[1]
            return [s[1], -spring(s[0]) - sgn * (drag + MU), 0.5 * s[1] ** 2 + potential(s[0])]

        def turned(_t, s):
            return s[1]

        turned.terminal = True
        turned.direction = 1.0 if sgn < 0 else -1.0
        sol = solve_ivp(
            rhs,
            (t, t + 50.0),
            [y, 0.0, c],
            method="DOP853",
            rtol=1e-12,
            atol=1e-14,
            events=turned,
            dense_output=True,
        )
        end = sol.y_events[0][0]
        pieces.append((t, float(sol.t_events[0][0]), sol.sol))
        t, y, c = float(sol.t_events[0][0]), float(end[0]), float(end[2])
        times.append(t)
        points.append(y)

    def cumulative(tau):
        for a, b, f in pieces:
            if a <= tau <= b:
                return float(f(tau)[2])
        return c

    return np.array(times), np.array(points), cumulative


@functools.cache
def _case(name):
    kernel, spring, potential, y0 = CASES[name]
    return kernel(), _reference(spring, potential, y0, TAU_END + 10.0), y0


@pytest.mark.parametrize("name", list(CASES))
def test_turning_points_match_an_independent_integration(name):
    kernel, (times, points, _), y0 = _case(name)
    law = get_law("viscous+quadratic+coulomb").with_restoring(kernel)
    tau_n, y_n = law.turning_points(VALUES, y0, tau_max=TAU_END, reference=y0)
    n = tau_n.size
    assert n > 20
    np.testing.assert_allclose(y_n, points[:n], rtol=0, atol=1e-6)
    np.testing.assert_allclose(tau_n, times[:n], rtol=0, atol=1e-4)


@pytest.mark.parametrize("name", list(CASES))
def test_pi_matches_an_independent_integration(name):
    kernel, (_, _, cumulative), y0 = _case(name)
    law = get_law("viscous+quadratic+coulomb").with_restoring(kernel)
    tau = np.linspace(0.0, TAU_END - 1.0, 57)  # grid points at every phase
    pi = law.pi_grid(tau, VALUES, np.array([y0]), 0.0, TAU_END, reference=y0)[0]
    truth = cumulative(TAU_END) - np.array([cumulative(x) for x in tau])
    assert np.max(np.abs(pi - truth)) < 1e-6 * truth[0]
    # the energy of the force's potential, not the linear spring's
    linear = get_law("viscous+quadratic+coulomb").pi_grid(
        tau, VALUES, np.array([y0]), 0.0, TAU_END, reference=y0
    )[0]
    assert np.max(np.abs(linear - truth)) > 1e-2 * truth[0]


def test_on_a_linear_spring_the_integrator_is_the_closed_form():
    linear = RestoringKernel(
        "linear", spring_kernel, potential_kernel, (), lambda y: 0.5 * np.square(y), np.asarray
    )
    law = get_law("viscous+coulomb")
    assert law.closed_form and not law.with_restoring(linear).closed_form
    tau = np.linspace(0.0, 80.0, 41)
    values = {"zeta": np.array([0.02, 0.005]), "mu_k": np.array([0.003, 0.01]), "mu_s_ratio": 1.2}
    y0 = np.array([1.0, 0.7])
    for end in (60.0, None):
        closed = law.pi_grid(tau, values, y0, 0.0, end)
        ours = law.with_restoring(linear).pi_grid(tau, values, y0, 0.0, end)
        np.testing.assert_allclose(ours, closed, rtol=0, atol=1e-6 * float(np.max(closed)))
    with pytest.raises(ValueError, match="no closed form on the linear"):
        law.with_restoring(linear).pi_grid(tau, values, y0, method="closed")


def test_a_fitted_force_gives_no_kernel_before_it_is_measured():
    with pytest.raises(ValueError, match="measured from the record first"):
        get_restoring("duffing").kernel()
    assert get_restoring("linear").kernel() is None
    assert duffing(0.1).kernel() == duffing(0.1).kernel() != duffing(0.2).kernel()


def test_a_run_on_a_linear_spring_is_prepared_and_fitted_as_before(bundled_run):
    """The bundled run (no ``restoring``): its energy, grid and law are the linear
    spring's, so that its fit is the closed form's, unchanged."""
    from bayestribo.inference.build import build_posterior
    from bayestribo.inference.preparation import prepare

    prepared = prepare(bundled_run)
    decay = prepared.decay
    assert decay.restoring is None and prepared.data.restoring is None
    np.testing.assert_array_equal(decay.energy, 0.5 * (decay.y**2 + decay.yp**2))
    posterior = build_posterior(prepared.data)
    assert posterior.law.restoring is None and posterior.law.closed_form
    # the same increments declared on a pendulum: the law takes it from the data, and
    # the averaged model, which has no form there, is refused by name
    import dataclasses

    from bayestribo.errors import BayestriboError

    kernel = get_restoring("pendulum").kernel()
    on_pendulum = dataclasses.replace(prepared.data, restoring=kernel)
    law = build_posterior(on_pendulum).law
    assert law.restoring == kernel and not law.closed_form
    with pytest.raises(BayestriboError, match="no form on the pendulum's restoring force"):
        build_posterior(on_pendulum, model="averaged")


_GL_X, _GL_W = np.polynomial.legendre.leggauss(32)


def _averaged_half_cycle(energy, spring, potential):
    """The averaged energy balance of docs/restoring.md, Eq. 3, at energy E: the drag's
    loss ∫_{-A}^{A} g(v(x)) dx and the half period ∫ dx/v(x), v(x) = √(2(E - V(x))),
    V(A) = E, by Gauss-Legendre in φ (x = A sin φ: no singularity at the ends)."""
    a = math.sqrt(2.0 * energy)
    for _ in range(60):
        a -= (potential(a) - energy) / spring(a)
    phi = 0.5 * math.pi * _GL_X
    x = a * np.sin(phi)
    v = np.sqrt(2.0 * (energy - np.array([potential(s) for s in x])))
    jacobian = 0.5 * math.pi * _GL_W * a * np.cos(phi)
    drag = float(np.sum(jacobian * (2 * ZETA * v + C2 * v * v)))
    return drag, float(np.sum(jacobian / v))


@pytest.mark.parametrize("name", list(CASES))
def test_the_averaged_energy_balance_holds_to_second_order(name):
    """Eq. 3 of docs/restoring.md against the loss per half cycle of the ODE and of the
    package's integrator: at the half cycle's mean energy the averaging error is second
    order in the relative loss ε = ΔE/E (the energy changes by ε within the half cycle,
    symmetrically about its middle; measured 0.1 ε²), at its starting energy first
    order (measured 0.4-0.7 ε): the tolerances are ε² and ε."""
    kernel, (times, points, _), y0 = _case(name)
    _, spring, potential, _ = CASES[name]
    law = get_law("viscous+quadratic+coulomb").with_restoring(kernel)
    _, ours = law.turning_points(VALUES, y0, tau_max=TAU_END, reference=y0)
    for k in (0, 6, 18):
        a, b = abs(points[k]), abs(points[k + 1])
        loss = potential(a) - potential(b)
        eps = loss / potential(a)
        assert eps > 0.05  # a loss large enough for the orders to be told apart
        drag, half = _averaged_half_cycle(0.5 * (potential(a) + potential(b)), spring, potential)
        averaged = drag + MU * (a + b)  # the friction's work: μ times the distance
        assert abs(averaged - loss) < eps**2 * loss
        assert abs(half - (times[k + 1] - times[k])) < eps**2 * half
        start, _ = _averaged_half_cycle(potential(a), spring, potential)
        assert eps**2 * loss < abs(start + MU * (a + b) - loss) < eps * loss
        # the integrator's own half cycle loses what the ODE's does
        integrated = potential(abs(ours[k])) - potential(abs(ours[k + 1]))
        assert integrated == pytest.approx(loss, rel=1e-5)


@pytest.mark.parametrize("name", list(CASES))
def test_the_laws_loss_per_cycle_takes_the_restoring_force(name):
    """ΔE(A) of the law on the force: per cycle of its own motion, twice the half cycle's
    loss of V (against the ODE's half cycles, interpolated at their swings), and to
    first order the averaged Eq. 3 at the swing (within ε, as above), its terms'
    shares summing to it."""
    kernel, (_, points, _), y0 = _case(name)
    potential = CASES[name][2]
    law = get_law("viscous+quadratic+coulomb").with_restoring(kernel)
    a = np.abs(points[:20])
    swing = 0.5 * (a[1:] + a[:-1])
    loss = 2.0 * (np.array([potential(x) for x in a[:-1]]) - [potential(x) for x in a[1:]])
    own = law.swing_dissipation(swing[[2, 9]], VALUES, y0)[0]
    np.testing.assert_allclose(own, loss[[2, 9]], rtol=1e-5)
    parts = law.dissipation(swing[[2, 9]], VALUES, y0, by_term=True)
    total = law.dissipation(swing[[2, 9]], VALUES, y0)[0]
    np.testing.assert_allclose(sum(parts.values())[0], total, rtol=1e-12)
    eps = loss[[2, 9]] / np.array([potential(s) for s in swing[[2, 9]]]) / 2.0
    assert np.all(np.abs(total - loss[[2, 9]]) < eps * loss[[2, 9]])
    # the friction's share is 4μA, whatever the force
    np.testing.assert_allclose(parts["coulomb"][0], 4.0 * MU * swing[[2, 9]], rtol=1e-12)


@pytest.mark.parametrize("name", list(CASES))
def test_a_law_on_a_restoring_force_pickles(name):
    """A campaign's workers hand laws and results between processes."""
    import pickle

    kernel = _case(name)[0]
    law = get_law("viscous+coulomb").with_restoring(kernel)
    back = pickle.loads(pickle.dumps(law))
    assert back == law and back.restoring.coefficients == kernel.coefficients
    np.testing.assert_array_equal(
        back.restoring.potential([0.3, 1.0]), kernel.potential([0.3, 1.0])
    )


def test_fixed_steps_of_either_sign_are_the_same_steps_on_a_restoring_force():
    """The coarse model's steps=-8 on a nonlinear restoring force integrates with 8
    steps as steps=8 does (its integrator has no sum past the record to shorten), not
    with its default steps."""
    kernel, _, y0 = _case("duffing")
    law = get_law("viscous+quadratic+coulomb").with_restoring(kernel)
    tau = np.linspace(0.0, TAU_END - 1.0, 9)
    pi = {
        s: law.pi_grid(tau, VALUES, np.array([y0]), 0.0, TAU_END, reference=y0, steps=s)[0]
        for s in (8, -8, 0)
    }
    np.testing.assert_array_equal(pi[-8], pi[8])
    assert np.max(np.abs(pi[0] - pi[8])) > 0.0
