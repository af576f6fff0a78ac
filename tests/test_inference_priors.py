"""Prior objects and the check of a posterior piled on a prior bound."""

from __future__ import annotations

import numpy as np
import pytest

from bayestribo.inference.priors import (
    BOUND_FRACTION,
    BOUND_WIDTH,
    LogUniform,
    Normal,
    PriorSet,
    Uniform,
    piled_on_bounds,
)


def _priors():
    return PriorSet({"zeta": Uniform(0.0, 0.3), "mu_k": Uniform(0.0, 2.0), "y0": Normal(7, 0.07)})


def test_a_posterior_inside_the_support_or_flat_over_it_is_not_flagged():
    rng = np.random.default_rng(0)
    inside = np.column_stack(
        [
            rng.normal(0.0236, 0.001, 4000),
            rng.normal(0.0294, 0.002, 4000),
            rng.normal(7, 0.07, 4000),
        ]
    )
    assert piled_on_bounds(inside, _priors()) == []
    # A posterior that learns nothing (the prior itself) puts BOUND_WIDTH at the edge.
    flat = np.column_stack(
        [rng.uniform(0, 0.3, 4000), rng.uniform(0, 2, 4000), rng.normal(7, 0.07, 4000)]
    )
    assert piled_on_bounds(flat, _priors()) == []
    assert BOUND_WIDTH < BOUND_FRACTION / 5  # the margin between the two cases


@pytest.mark.parametrize("prior", [Uniform(0.0, 2.0), LogUniform(1e-3, 2.0)])
def test_a_posterior_against_an_upper_bound_is_flagged(prior):
    rng = np.random.default_rng(1)
    near = 2.0 - np.abs(rng.normal(0.0, 0.01, 4000))  # mass piled under the bound
    draws = np.column_stack([rng.normal(0.02, 0.001, 4000), near])
    got = piled_on_bounds(draws, PriorSet({"zeta": Uniform(0.0, 0.3), "mu_k": prior}))
    assert [g["parameter"] for g in got] == ["mu_k"]
    assert got[0]["bound"] == 2.0 and got[0]["fraction"] > 0.9


def test_the_lower_bound_is_a_physical_value_not_a_pile_up():
    rng = np.random.default_rng(2)
    at_zero = np.abs(rng.normal(0.0, 1e-6, 4000))  # ζ = 0: no viscous damping
    draws = np.column_stack([at_zero, rng.normal(0.03, 0.001, 4000)])
    assert piled_on_bounds(draws, PriorSet({"zeta": Uniform(0, 0.3), "mu_k": Uniform(0, 2)})) == []
