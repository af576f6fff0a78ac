"""A term the draws put at zero force leaves its other parameters unidentified
(bayestribo.inference.identifiability)."""

from __future__ import annotations

import numpy as np
import pytest

from bayestribo.inference.identifiability import unidentified_reasons
from bayestribo.model.laws import get_law

NAMES = ["mu_k", "mu_s_ratio", "zeta_alpha", "alpha", "y0"]


def _draws(zeta: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    n = zeta.size
    return np.column_stack(
        [
            rng.normal(0.0194, 1e-4, n),
            rng.uniform(5.5, 6.5, n),
            zeta,
            rng.uniform(0.0, 3.0, n),
            rng.normal(-1.29, 1e-4, n),
        ]
    )


def test_a_power_drag_at_zero_names_alpha_and_the_law_without_it():
    rng = np.random.default_rng(1)
    draws = _draws(np.abs(rng.normal(0.0, 5e-4, 4000)), rng)
    reasons = unidentified_reasons(draws, NAMES, get_law("coulomb+power"))
    assert len(reasons) == 1
    assert "zeta_alpha" in reasons[0] and "(alpha)" in reasons[0]
    assert "law='coulomb'" in reasons[0]


def test_a_power_drag_away_from_zero_is_not_named():
    rng = np.random.default_rng(2)
    draws = _draws(rng.normal(0.01, 5e-4, 4000), rng)
    assert unidentified_reasons(draws, NAMES, get_law("coulomb+power")) == []


def test_friction_at_zero_names_the_static_ratio():
    rng = np.random.default_rng(3)
    draws = _draws(rng.normal(0.01, 5e-4, 4000), rng)
    draws[:, 0] = np.abs(rng.normal(0.0, 1e-4, 4000))
    reasons = unidentified_reasons(draws, NAMES, get_law("coulomb+power"))
    assert len(reasons) == 1 and "mu_s_ratio" in reasons[0] and "law='power'" in reasons[0]


def test_no_more_increments_than_parameters_is_named_and_fewer_parameters_are_not():
    """The count rule: five sampled parameters on five increments are not identified
    (ζ_α well clear of its null), on six they are not named by it."""
    rng = np.random.default_rng(2)
    draws = _draws(rng.uniform(0.02, 0.04, 4000), rng)
    law = get_law("coulomb+power")
    assert unidentified_reasons(draws, NAMES, law) == []
    reasons = unidentified_reasons(draws, NAMES, law, n_increments=5)
    assert len(reasons) == 1
    assert "5 sampled parameters" in reasons[0] and "5 increments" in reasons[0]
    assert "coulomb+power" in reasons[0]
    assert unidentified_reasons(draws, NAMES, law, n_increments=6) == []


def test_a_bad_number_of_increments_names_the_argument():
    law = get_law("coulomb+power")
    draws = np.zeros((4, len(NAMES)))
    for bad in (0, -3, 2.5, True):
        with pytest.raises(ValueError, match="n_increments: expected a positive integer"):
            unidentified_reasons(draws, NAMES, law, n_increments=bad)
