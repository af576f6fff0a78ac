"""A trend against a covariate: a straight line, or a threshold (the paper's μ_k)."""

from __future__ import annotations

import doctest

import numpy as np
import pytest

from bayestribo.reports import trends
from bayestribo.reports.trends import threshold_test

#: The glycerol–water series' viscosities [mm²/s] (Eq. 43 at 9, 8, 6, 3, 2.3, 0.55 % water).
NU = np.array([214.0, 252.0, 357.0, 626.0, 719.0, 1031.0])


def test_the_examples_hold():
    assert doctest.testmod(trends).failed == 0


def test_a_threshold_is_found_where_the_means_are_constant_above_it():
    # μ_k constant down to 357 mm²/s and rising below it, each mean known to 0.0005
    y = 0.0294 + 2e-4 * np.maximum(357.0 - NU, 0.0)
    found = threshold_test(NU, y, np.full(NU.size, 5e-4))
    assert found.has_threshold and found.flat_above and not found.linear_fits
    assert 252.0 < found.threshold < 626.0
    assert found.text("mm²/s").startswith("a threshold: constant above")


def test_a_straight_line_is_said_to_fit_and_no_threshold_is_made_up():
    rng = np.random.default_rng(3)
    sd = np.full(NU.size, 1e-3)
    y = 0.01 + 1.4e-5 * NU + rng.normal(0.0, 1e-3, NU.size)
    found = threshold_test(NU, y, sd)
    assert found.linear_fits and not found.has_threshold
    assert found.text("mm²/s").startswith("the straight line fits")


@pytest.mark.parametrize(
    ("x", "y", "sd", "match"),
    [
        ([1, 2, 3], [1, 2, 3], [1, 1, 1], "at least 4 distinct"),
        ([1, 2, 3, 4], [1, 2, 3], [1, 1, 1, 1], "one length"),
        ([1, 2, 3, 4], [1, 2, 3, 4], [1, 0, 1, 1], "sd > 0"),
    ],
)
def test_bad_input_is_refused_naming_what_was_expected(x, y, sd, match):
    with pytest.raises(ValueError, match=match):
        threshold_test(x, y, sd)
