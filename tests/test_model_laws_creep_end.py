"""A creep to rest ends where the record's motion was seen to end (``creep_end``).

A power drag below α = 1 ends its motion by an overdamped creep that never reaches
rest in a finite time (:mod:`bayestribo.model.laws._creep`). A record that holds its
stop has its Π end at the detected stop τ_d inside that creep; the model's Π, summed
to the end of motion, integrates the creep up to τ_d too
(:meth:`bayestribo.model.laws.Law.pi_grid`'s ``creep_end``, passed by
:meth:`bayestribo.inference.likelihood.PiLikelihood.law_pi` to the likelihood, the
fused posterior's law source and the piecewise Π alike).

The reference integrates y'' = -y - c|y'|^α sgn y' with C = ∫E dτ as a third state by
LSODA at rtol 1e-12 (as ``tests/test_model_laws_creep.py`` does), up to the end given.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bayestribo.inference.fused import LawSource
from bayestribo.inference.likelihood import PiLikelihood
from bayestribo.inference.piece_pi import longest_motion_pi
from bayestribo.model.laws import get_law
from bayestribo.model.laws.base import harmonic_power_integral
from bayestribo.model.laws.integrator import compiled_law
from bayestribo.signal.increments import PiData

Y0 = 1.0
TAU = np.linspace(0.0, 40.0, 41)
# α, ζ_α and an end inside the creep: the creep starts before τ = 10 and holds more
# than 1e-6 of Π(0) past the last grid point before the end (at α = 0.9 its ∫E falls
# below 1e-12 of Π(0) by τ = 30)
CASES = [
    (0.3, 0.2, 30.5),
    (0.3, 0.2, 47.25),
    (0.5, 0.2, 30.5),
    (0.5, 0.2, 47.25),
    (0.7, 0.5, 10.25),
    (0.7, 0.5, 20.5),
    (0.9, 0.5, 8.75),
    (0.9, 0.5, 9.5),
]


def _c(zeta: float, alpha: float) -> float:
    return 2.0 * math.pi * zeta * Y0 ** (1.0 - alpha) / harmonic_power_integral(alpha + 1.0)


def _integral(zeta: float, alpha: float, end: float):
    """solve_ivp's C(τ) = ∫₀^τ E up to ``end`` (a dense solution)."""
    c = _c(zeta, alpha)

    def rhs(t, s):
        y, v, _ = s
        return [v, -y - c * abs(v) ** alpha * np.sign(v), 0.5 * (y * y + v * v)]

    return solve_ivp(
        rhs, (0.0, end), [Y0, 0.0, 0.0], method="LSODA", rtol=1e-12, atol=1e-16, dense_output=True
    )


def _pi(zeta, alpha, tau, creep_end, tau_end=None, steps=0):
    values = {"zeta_alpha": np.array([zeta]), "alpha": np.array([alpha])}
    return get_law("power").pi_grid(
        tau,
        values,
        [Y0],
        tau_end=tau_end,
        reference=Y0,
        method="integrate",
        steps=steps,
        creep_end=creep_end,
    )[0]


def _creep_start(zeta: float, alpha: float) -> float:
    """τ of the last turning point: where the creep starts."""
    module = compiled_law(*get_law("power")._layout[0])
    c = np.array([_c(zeta, alpha), alpha])
    times, _ = module.turns(Y0, c, 1.0, 0.0, math.inf, 10_000)
    return float(times[-1])


@pytest.mark.parametrize(("alpha", "zeta", "end"), CASES)
def test_the_creep_up_to_its_end_is_the_equation_of_motions(alpha, zeta, end):
    """Summed to the end of motion with the creep ending at ``end``: Π at the grid
    points up to it within 1e-7 of Π(0) of solve_ivp's ∫_τ^end E (the integrator's
    own accuracy is ~1e-8), 0 past it; a creep that holds more than 1e-6 of Π(0) past
    the last grid point before the end, which the creep to rest would have added."""
    start = _creep_start(zeta, alpha)
    assert 0.0 < start < 10.0
    sol = _integral(zeta, alpha, end)
    before = TAU < end
    ref = sol.y[2, -1] - sol.sol(TAU[before])[2]
    pi = _pi(zeta, alpha, TAU, end)
    assert np.all(np.isfinite(pi))
    assert np.max(np.abs(pi[before] - ref)) < 1e-7 * ref[0]
    assert np.all(pi[~before] == 0.0)
    assert ref[-1] > 1e-6 * ref[0]
    if alpha > 1.0 / 3.0:
        # to rest, the creep past ``end`` adds to every grid point
        to_rest = _pi(zeta, alpha, TAU, None)
        assert np.min(to_rest[before] - pi[before]) > 1e-7 * ref[0]
    else:
        assert np.all(np.isnan(_pi(zeta, alpha, TAU, None)))  # its ∫E to rest diverges


@pytest.mark.parametrize(("alpha", "zeta"), sorted({c[:2] for c in CASES}))
def test_a_creep_that_starts_after_its_end_adds_nothing(alpha, zeta):
    """An end before the creep starts: Π is the motion's up to the creep's start
    (the last turning point), within 1e-7 of Π(0) of solve_ivp's."""
    start = _creep_start(zeta, alpha)
    sol = _integral(zeta, alpha, start)
    before = TAU < start
    ref = sol.y[2, -1] - sol.sol(TAU[before])[2]
    pi = _pi(zeta, alpha, TAU, 0.5 * start)
    assert np.max(np.abs(pi[before] - ref)) < 1e-7 * ref[0]
    assert np.all(pi[~before] == 0.0)


def test_the_coarse_model_takes_the_same_creep_end():
    """The optimiser's coarse model (steps < 0) ends its creep at the same time:
    within 1e-5 of Π(0) of the default steps."""
    fast = _pi(0.5, 0.5, TAU, 30.5)
    coarse = _pi(0.5, 0.5, TAU, 30.5, steps=-8)
    assert np.max(np.abs(coarse - fast)) < 1e-5 * fast[0]


def test_an_end_at_or_past_the_records_end_or_none_changes_nothing():
    """``creep_end`` is read only below ``tau_end``: at or past it, or None, or
    infinite, the same Π to the bit."""
    for tau_end in (None, 30.5):
        base = _pi(0.5, 0.5, TAU, None, tau_end)
        for creep_end in (math.inf, 30.5, 90.0):
            if tau_end is None and math.isfinite(creep_end):
                continue
            assert np.array_equal(_pi(0.5, 0.5, TAU, creep_end, tau_end), base)


@pytest.mark.parametrize("law", ["viscous", "quadratic", "viscous+coulomb", "coulomb+power"])
def test_a_motion_without_a_creep_ignores_it(law):
    """A motion that ends without a creep (a drag above α = 1, friction) or the closed
    form: the same Π to the bit with a creep end inside its motion."""
    lw = get_law(law)
    rng = np.random.default_rng(7)
    values = {}
    for p in lw.parameters:
        spec = p.prior(Y0)
        values[p.name] = rng.uniform(float(spec["low"]), 0.2 * float(spec["high"]), 6)
    if "alpha" in values:
        values["alpha"] = rng.uniform(1.2, 2.5, 6)
    y0 = np.full(6, Y0)
    base = lw.pi_grid(TAU, values, y0, reference=Y0)
    ended = lw.pi_grid(TAU, values, y0, reference=Y0, creep_end=12.5)
    assert np.array_equal(base, ended, equal_nan=True)
    assert np.isfinite(base).any()


def _data(zeta: float, alpha: float, end: float) -> PiData:
    """A record of the creeping motion whose analysis ends at its detected stop
    ``end``: the increments are solve_ivp's ∫E between the grid points and ``end``."""
    grid = np.append(TAU[TAU < end], end)
    sol = _integral(zeta, alpha, end)
    cum = sol.sol(grid)[2]
    m = grid.size - 1
    return PiData(
        tau_grid=grid,
        increments=np.diff(cum),
        variance=np.full(m, 1e-12),
        energy_squared=np.ones(m),
        motion_ended=True,
        y0=Y0,
        yp0=0.0,
        noise_bias=np.zeros(m),
        offset_design=np.zeros((m, 3)),
    )


@pytest.mark.parametrize(
    ("alpha", "zeta", "end"), [(0.3, 0.2, 30.5), (0.5, 0.2, 30.5), (0.7, 0.5, 10.25)]
)
def test_the_likelihoods_last_increment_ends_at_the_records_stop(alpha, zeta, end):
    """A record that holds its stop inside the creep: the model's increments at the
    truth are the record's, the last one included, within 1e-7 of Π(0) (the creep to
    rest would add its ∫E past the stop to the last one, or be NaN at α <= 1/3); the
    fused posterior's law source and the piecewise Π take the same Π to the bit."""
    data = _data(zeta, alpha, end)
    lik = PiLikelihood(data, law=get_law("power"))
    params = {"zeta_alpha": np.array([zeta]), "alpha": np.array([alpha]), "y0": np.array([Y0])}
    model = lik.model_increments(params)[0]
    total = float(np.sum(data.increments))
    assert np.max(np.abs(model - data.increments)) < 1e-7 * total
    assert data.increments[-1] > 1e-6 * total
    # the model's creep run to rest misses the last increment by its ∫E past the stop
    values = {k: v for k, v in params.items() if k != "y0"}
    to_rest = get_law("power").pi_grid(data.tau_grid[:-1], values, [Y0], reference=Y0)[0]
    assert not to_rest[-1] - data.increments[-1] < 1e-6 * total  # (NaN at α <= 1/3)
    pi = lik.model_pi(params)
    source = LawSource(
        lik, (("zeta_alpha", 0, math.nan), ("alpha", 1, math.nan), ("y0", 2, math.nan))
    )
    assert np.array_equal(source.pi(np.array([[zeta, alpha, Y0]])), pi)
    grid = data.tau_grid[:-1]
    assert np.array_equal(longest_motion_pi(lik, params, grid), pi)
