"""A power drag below α = 1 ends its motion by an overdamped creep to rest, integrated
(:mod:`bayestribo.model.laws._creep`) against ``solve_ivp`` of the same equation.

The reference integrates y'' = -y - c|y'|^α sgn y' with C = ∫E dτ as a third state by
LSODA at rtol 1e-12 (Radau at the same tolerance is off by ~2e-6 of Π(0) at α = 0.3,
where |y'|^α is not smooth at the turning points, and LSODA and DOP853 agree to 1e-12
there). To the end of motion its rest past τ = 1e7 is the quasi-static creep's
closed form, c^(1/α) y^(3-1/α)/(2(3 - 1/α)).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bayestribo.model.laws import get_law
from bayestribo.model.laws.base import harmonic_power_integral
from bayestribo.model.laws.integrator import compiled_law

Y0 = 1.0
TAU = np.linspace(0.0, 55.0, 56)
TAU_END = 60.0


def _c(zeta: float, alpha: float) -> float:
    return 2.0 * math.pi * zeta * Y0 ** (1.0 - alpha) / harmonic_power_integral(alpha + 1.0)


def _reference(zeta: float, alpha: float, tau_end: float) -> np.ndarray:
    c = _c(zeta, alpha)

    def rhs(t, s):
        y, v, _ = s
        return [v, -y - c * abs(v) ** alpha * np.sign(v), 0.5 * (y * y + v * v)]

    end = tau_end if math.isfinite(tau_end) else 1e7
    sol = solve_ivp(
        rhs, (0.0, end), [Y0, 0.0, 0.0], method="LSODA", rtol=1e-12, atol=1e-16, dense_output=True
    )
    total = sol.y[2, -1]
    if not math.isfinite(tau_end):
        y = abs(sol.y[0, -1])
        total += c ** (1.0 / alpha) * y ** (3.0 - 1.0 / alpha) / (2.0 * (3.0 - 1.0 / alpha))
    return total - sol.sol(TAU)[2]


def _pi(zeta: float, alpha: float, tau_end: float | None, steps: int = 0) -> np.ndarray:
    values = {"zeta_alpha": np.array([zeta]), "alpha": np.array([alpha])}
    law = get_law("power")
    return law.pi_grid(
        TAU, values, [Y0], tau_end=tau_end, reference=Y0, method="integrate", steps=steps
    )[0]


def _creep_start(zeta: float, alpha: float) -> float:
    """τ of the last turning point: where the creep starts."""
    module = compiled_law(*get_law("power")._layout[0])
    c = np.array([_c(zeta, alpha), alpha])
    times, _ = module.turns(Y0, c, 1.0, 0.0, math.inf, 10_000)
    return float(times[-1])


# ζ_α whose creep starts before τ = 45 holding more than 1e-6 of Π(0) (at α = 0.9 and
# ζ_α = 0.2 it holds 4e-13)
CASES = [(a, z) for a in (0.3, 0.4, 0.5, 0.7) for z in (0.2, 0.5)] + [(0.9, 0.5), (0.9, 0.8)]


@pytest.mark.parametrize(("alpha", "zeta"), CASES)
def test_the_creep_up_to_the_records_end_is_the_equation_of_motions(alpha, zeta):
    """Up to a record's end inside the creep: Π within 1e-7 of Π(0) of solve_ivp's (the
    integrator reaches 2e-9 to 1.5e-8), with the grid points on the creep (it starts
    before τ = 45) and a creep that holds more than 1e-6 of Π(0), which the quasi-static
    rule refused."""
    start = _creep_start(zeta, alpha)
    assert start < 45.0
    pi = _pi(zeta, alpha, TAU_END)
    ref = _reference(zeta, alpha, TAU_END)
    assert np.all(np.isfinite(pi))
    on_creep = TAU > start
    assert on_creep.sum() >= 10
    assert ref[np.argmax(on_creep)] > 1e-6 * ref[0]
    assert np.max(np.abs(pi - ref)) < 1e-7 * ref[0]


@pytest.mark.parametrize(("alpha", "zeta"), [c for c in CASES if c[0] > 1.0 / 3.0])
def test_the_creep_to_rest_is_the_equation_of_motions(alpha, zeta):
    """To the end of motion (α > 1/3, where the creep's ∫E converges): within 1e-7 of
    Π(0), every grid point (most on the creep) and the rest past the record."""
    pi = _pi(zeta, alpha, None)
    ref = _reference(zeta, alpha, math.inf)
    assert np.all(np.isfinite(pi))
    assert np.max(np.abs(pi - ref)) < 1e-7 * ref[0]


@pytest.mark.parametrize("steps", [-8, 128])
def test_a_fixed_step_model_integrates_the_same_creep(steps):
    """The coarse model of the optimiser (steps < 0) and the fixed-step reference (> 0)
    take the same creep: within 1e-5 and 1e-7 of Π(0) of the default steps."""
    fast = _pi(0.5, 0.5, None)
    fixed = _pi(0.5, 0.5, None, steps)
    assert np.all(np.isfinite(fixed))
    tolerance = 1e-5 if steps < 0 else 1e-7
    assert np.max(np.abs(fixed - fast)) < tolerance * fast[0]


@pytest.mark.parametrize("alpha", [0.2, 0.3, 1.0 / 3.0])
def test_a_creep_that_never_ends_is_outside_the_domain_only_to_the_end_of_motion(alpha):
    """At α <= 1/3 the creep's ∫E to rest diverges: the row is NaN to the end of motion,
    and finite up to a record's end."""
    assert np.all(np.isnan(_pi(0.2, alpha, None)))
    assert np.all(np.isfinite(_pi(0.2, alpha, TAU_END)))
