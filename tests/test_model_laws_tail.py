"""The integrator's sum past the record: the averaged tail and the drag's creep to rest
against the half cycles' own sum (:mod:`bayestribo.model.laws._core`).

The reference is the exact half-cycle sum with a fixed number of steps per half cycle
(``steps=128``), which never takes a shortcut: every half cycle is integrated up to the
cap of half cycles past the record, or to the end of the motion.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bayestribo.model.laws import get_law
from bayestribo.model.laws.integrator import compiled_law

# Every registered drag, alone and with a friction that stops the motion (coulomb) or
# vanishes with the amplitude (hysteretic). Values put the decay of the record's
# 30 half cycles at ΔE/E ~ 1-6 % a half cycle, the motion going on past it.
DRAG_CASES = [
    ("power", {"zeta_alpha": 0.01, "alpha": 1.5}),
    ("power", {"zeta_alpha": 0.01, "alpha": 2.0}),
    ("power", {"zeta_alpha": 0.01, "alpha": 3.0}),
    ("quadratic", {"c2": 0.01}),
    ("viscous+quadratic", {"zeta": 0.002, "c2": 0.01}),
    ("quadratic+hysteretic", {"c2": 0.01, "eta": 0.0005}),
    # a quadratic drag down to where a small hysteretic loss takes over (the bundled
    # run's multi-start): the local power falls from 2 to 1 down the tail
    ("quadratic+hysteretic", {"c2": 0.018, "eta": 4.5e-5}),
    ("coulomb+power", {"mu_k": 2e-4, "mu_s_ratio": 1.0, "zeta_alpha": 0.01, "alpha": 2.0}),
    ("coulomb+quadratic", {"mu_k": 2e-4, "mu_s_ratio": 1.0, "c2": 0.01}),
]
TAU = np.linspace(0.0, 95.0, 31)  # a record of 30 half cycles, ending in the motion
Y0 = 7.4


def _pi(law: str, values: dict, steps: int) -> np.ndarray:
    the_law = get_law(law)
    vals = {k: np.array([v]) for k, v in values.items()}
    return the_law.pi_grid(TAU, vals, [Y0], reference=Y0, method="integrate", steps=steps)[0]


@pytest.mark.parametrize(("law", "values"), DRAG_CASES)
def test_the_sum_past_the_record_agrees_with_the_half_cycles_sum(law, values):
    """Π to the end of motion within 1e-8 of Π(0) and 1e-6 of the last increment's Π
    (the tail past the record) of the half cycles' sum: the half cycles' own sum at 64
    and 128 steps differs by up to 5e-7 of it."""
    fast = _pi(law, values, 0)
    exact = _pi(law, values, 128)
    assert np.all(np.isfinite(exact)) and np.all(np.isfinite(fast))
    tolerance = 1e-8 * exact[0] + 1e-6 * exact[-1]
    assert np.max(np.abs(fast - exact)) < tolerance


def _module(law: str):
    return compiled_law(*get_law(law)._layout[0])


def _coefficients(law: str, values: dict) -> np.ndarray:
    vals = {k: np.array([v]) for k, v in values.items()}
    return get_law(law).coefficients(vals, Y0)[0]


@pytest.mark.parametrize(
    ("law", "values", "amplitude"),
    [
        ("power", {"zeta_alpha": 0.003, "alpha": 1.5}, 2.0),
        ("power", {"zeta_alpha": 0.003, "alpha": 2.0}, 2.0),
        ("power", {"zeta_alpha": 0.003, "alpha": 3.0}, 4.0),
        ("quadratic", {"c2": 0.003}, 1.0),
        ("viscous+quadratic", {"zeta": 0.001, "c2": 0.003}, 1.0),
        # its first span's interpolants miss their tolerance: taken on a half of it
        ("quadratic+hysteretic", {"c2": 0.018, "eta": 4.5e-5}, 0.5),
    ],
)
@pytest.mark.parametrize("count", [300, 20_000])
def test_the_averaged_tail_is_the_sum_of_the_half_cycles_it_stands_for(
    law, values, amplitude, count
):
    """The averaged tail from a turning point over ``count`` half cycles (or to where
    the rest is below 1e-12 of it) against those half cycles integrated one by one: the
    record ends at the first point, so Π(0) of a start from rest sums ∫E over the
    half cycles up to the cap of 20,000 past the record."""
    module = _module(law)
    c = _coefficients(law, values)
    size = module.LADDER[-1] + 1
    work = np.empty(size), np.empty(size), np.empty((2, size))
    tail = module.averaged_tail(
        amplitude, c, 1.0, count, 1e-12 * amplitude**2, module._TABLES, module._OFFSETS, *work
    )
    assert math.isfinite(tail)  # taken, not left to the half cycles
    if count == 20_000:
        exact, _ = module.grid(
            np.zeros(1), np.array([amplitude]), c[None], np.ones(1), 0.0, math.inf, 128
        )
        exact = exact[0, 0]
    else:
        # the first `count` half cycles: Π at the turning point after them, subtracted
        times, _ = module.turns(amplitude, c, 1.0, 0.0, math.inf, count + 1)  # 0 first
        pi, _ = module.grid(
            np.array([0.0, times[count]]),
            np.array([amplitude]),
            c[None],
            np.ones(1),
            0.0,
            math.inf,
            128,
        )
        exact = pi[0, 0] - pi[0, 1]
    assert tail == pytest.approx(exact, rel=1e-6)


def test_an_averaged_tail_of_a_decay_that_quickens_is_left_to_the_half_cycles():
    """Below α = 1 the drop per half cycle grows as the amplitude falls: no averaged
    tail (the motion ends after a few tens of half cycles)."""
    module = _module("power")
    c = _coefficients("power", {"zeta_alpha": 0.01, "alpha": 0.7})
    size = module.LADDER[-1] + 1
    work = np.empty(size), np.empty(size), np.empty((2, size))
    tail = module.averaged_tail(1.0, c, 1.0, 20_000, 1e-12, module._TABLES, module._OFFSETS, *work)
    assert math.isnan(tail)


def test_a_drag_below_alpha_one_creeps_to_rest_with_a_finite_pi():
    """A power drag below α = 1 ends the motion by an overdamped creep to rest, which
    the integrator follows (:mod:`bayestribo.model.laws._creep`) with the default steps
    and with fixed steps alike (the reference of 128 steps a half cycle, every half
    cycle integrated): the two within 1e-8 of Π(0). Both against solve_ivp through the
    creep: ``tests/test_model_laws_creep.py``."""
    law = get_law("power")
    alpha = 0.77  # the bundled run's posterior of a power drag alone
    values = {"zeta_alpha": np.array([0.025]), "alpha": np.array([alpha])}
    fast = law.pi_grid(TAU, values, [Y0], reference=Y0, method="integrate")[0]
    exact = law.pi_grid(TAU, values, [Y0], reference=Y0, method="integrate", steps=128)[0]
    assert np.all(np.isfinite(exact))
    assert np.all(np.isfinite(fast))
    assert np.max(np.abs(fast - exact)) < 1e-8 * exact[0]


@pytest.mark.parametrize("alpha", [0.4, 0.5, 0.77, 0.95])
def test_the_creeps_integral_is_the_quasi_static_balances_in_closed_form(alpha):
    """For g = c w^α the quasi-static creep from a, corrected to first order in its
    inertia (w = w₀(1 + ε), ε = 1/g'(w₀)² = w₀²/(αy)², w₀ = (y/c)^(1/α)), holds
    ∫₀^a [(y²/2)(1 - ε)/w₀ + w₀/2] dy = c^(1/α) a^(3-1/α) / (2(3 - 1/α))
    + (1 - 1/α²) a^(1+1/α) / (2 c^(1/α) (1 + 1/α)), to 1e-6 (α > 1/3)."""
    module = _module("power")
    c = _coefficients("power", {"zeta_alpha": 0.025, "alpha": alpha})
    a = 1e-4
    k = 1.0 / alpha
    closed = c[0] ** k * a ** (3 - k) / (2 * (3 - k)) + (1 - k * k) * a ** (1 + k) / (
        2 * c[0] ** k * (1 + k)
    )
    assert module.creep_integral(a, c) == pytest.approx(closed, rel=1e-6)


def test_a_creep_that_never_ends_leaves_the_row_outside_the_laws_domain():
    """At α <= 1/3 the creep's energy integral diverges: the row stays NaN."""
    module = _module("power")
    c = _coefficients("power", {"zeta_alpha": 0.025, "alpha": 0.3})
    assert math.isnan(module.creep_integral(1e-4, c))
    law = get_law("power")
    values = {"zeta_alpha": np.array([0.025]), "alpha": np.array([0.3])}
    assert np.all(np.isnan(law.pi_grid(TAU, values, [Y0], reference=Y0, method="integrate")))


# The coarse model of the optimiser's multi-start (steps=-8): the half cycles of 8 steps
# each, as steps=8 integrates them, with the sum past the record shortened as the
# default model's is. A law whose friction vanishes with the amplitude (its motion never
# stopped by it) ends geometrically; a decay that slows takes the averaged tail of its
# own 8-step half cycles, up to the same cap of 20,000 past the record.
COARSE_CASES = [
    *DRAG_CASES,
    ("quadratic+hysteretic", {"c2": 1e-6, "eta": 0.04}),
    ("quadratic", {"c2": 0.034}),
]


@pytest.mark.parametrize(("law", "values"), COARSE_CASES)
def test_the_coarse_models_shortened_sum_is_its_half_cycles_sum(law, values):
    """steps=-8 within 1e-9 of Π(0) and 1e-6 of the tail past the record of steps=8,
    which integrates every half cycle of 8 steps (the coarse model's own error against
    the exact one is ~1e-5 of Π(0))."""
    shortened = _pi(law, values, -8)
    summed = _pi(law, values, 8)
    assert np.all(np.isfinite(summed)) and np.all(np.isfinite(shortened))
    tolerance = 1e-9 * summed[0] + 1e-6 * summed[-1]
    assert np.max(np.abs(shortened - summed)) < tolerance


def test_a_record_that_ends_in_the_motion_has_the_same_coarse_model_either_way():
    """Truncated at the end of the record, nothing is summed past it: steps=-8 and
    steps=8 give the same Π to rounding."""
    law = get_law("power")
    vals = {"zeta_alpha": np.array([0.01]), "alpha": np.array([2.0])}
    both = [
        law.pi_grid(TAU, vals, [Y0], tau_end=TAU[-1], reference=Y0, method="integrate", steps=s)
        for s in (8, -8)
    ]
    np.testing.assert_allclose(both[1], both[0], rtol=1e-14, atol=0.0)


@pytest.mark.parametrize(
    ("law", "values", "amplitude"),
    [
        ("power", {"zeta_alpha": 0.003, "alpha": 2.0}, 2.0),
        ("quadratic", {"c2": 0.003}, 1.0),
    ],
)
def test_the_averaged_tail_of_fixed_steps_is_the_sum_of_those_half_cycles(law, values, amplitude):
    """The averaged tail of half cycles of 8 steps each (``fixed=8``: those the coarse
    model integrates) over the 20,000 past a record that ends at the first point,
    against the same half cycles integrated one by one (steps=8); the default's tail
    (the ladder's half cycles) is another sum, off by the 8 steps' own error."""
    module = _module(law)
    c = _coefficients(law, values)
    size = module.LADDER[-1] + 1
    work = np.empty(size), np.empty(size), np.empty((2, size))
    table = module.nodes(0.0, 8)
    negligible = 1e-12 * amplitude**2
    tail = module.averaged_tail(
        amplitude, c, 1.0, 20_000, negligible, table, np.zeros(1, np.int64), *work, 8
    )
    assert math.isfinite(tail)  # taken, not left to the half cycles
    summed, _ = module.grid(
        np.zeros(1), np.array([amplitude]), c[None], np.ones(1), 0.0, math.inf, 8
    )
    assert tail == pytest.approx(summed[0, 0], rel=1e-6)
    ladder = module.averaged_tail(
        amplitude, c, 1.0, 20_000, negligible, module._TABLES, module._OFFSETS, *work
    )
    assert abs(ladder - summed[0, 0]) > abs(tail - summed[0, 0])
