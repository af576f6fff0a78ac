"""A static friction the data bound from above only is a bound (``inference/flatness.py``).

A record that never sticks bounds μ_s by a turning point that did not stick; its last,
small turning points cannot tell a stick from one more small half cycle, so the upper
edge is soft and the posterior is not flat over its prior: a torsion wheel's record gave
μ_s/μ_k = 2.8 [1.1, 4.4] (Kolmogorov–Smirnov distance 0.19 from flat, its density at 1
two thirds of its highest), a central interval whose lower side is the prior's.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from bayestribo.inference.flatness import (
    END_DENSITY,
    bound_interval,
    end_density,
    is_bound,
    is_flat,
    prior_flatness,
)
from bayestribo.inference.priors import PriorSet, Uniform


def _fit(draws):
    return SimpleNamespace(
        priors=PriorSet({"mu_s_ratio": Uniform(1.0, 10.0)}), samples=lambda name: draws
    )


def _soft_edge(n=4000, seed=0):
    """Draws of a density 0.65 at 1 rising to 1 at 3, falling to 0 at 5."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(1.0, 5.0, 8 * n)
    density = np.where(x < 3.0, 0.65 + 0.35 * (x - 1.0) / 2.0, (5.0 - x) / 2.0)
    return x[rng.uniform(0.0, 1.0, x.size) < density][:n]


def test_a_soft_upper_edge_from_the_prior_end_is_a_bound():
    fit = _fit(_soft_edge())
    assert not is_flat(prior_flatness(fit, "mu_s_ratio"))  # not flat: the old rule missed it
    assert end_density(fit, "mu_s_ratio") >= END_DENSITY
    assert is_bound(fit, "mu_s_ratio")
    low, high = bound_interval(fit, "mu_s_ratio", fit.samples("mu_s_ratio"))
    assert low == 1.0 and high == pytest.approx(np.quantile(fit.samples("mu_s_ratio"), 0.95))
    # the static friction it sets, too
    assert is_bound(fit, "static_friction_displacement")


def test_a_peak_away_from_the_prior_end_is_a_measurement():
    rng = np.random.default_rng(1)
    draws = rng.normal(2.5, 0.5, 8000)
    draws = draws[draws > 1.0][:4000]  # reaches the end, a tenth of the peak there
    fit = _fit(draws)
    assert end_density(fit, "mu_s_ratio") < END_DENSITY
    assert not is_bound(fit, "mu_s_ratio")


def test_only_the_static_friction_takes_the_end_density_rule():
    # a damping ratio piled towards zero is left to its own checks (at the bound)
    draws = _soft_edge() - 1.0
    fit = SimpleNamespace(priors=PriorSet({"zeta": Uniform(0.0, 10.0)}), samples=lambda n: draws)
    assert end_density(fit, "zeta") >= END_DENSITY
    assert not is_bound(fit, "zeta")
