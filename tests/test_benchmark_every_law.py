"""``benchmarks/every_law.py --compare``: two results side by side, each posterior
mean's shift in the first one's posterior sd."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def every_law():
    spec = importlib.util.spec_from_file_location("every_law", ROOT / "benchmarks" / "every_law.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _results(rows):
    return {"recordings": {"run": rows}}


def test_the_largest_shift_is_in_the_base_posteriors_sd(every_law):
    base = _results(
        {
            "quadratic": {
                "over_default": 6.0,
                "converged": True,
                "posterior": {"c2": [1.0, 0.5], "y0": [2.0, 0.1]},
            }
        }
    )
    new = _results(
        {
            "quadratic": {
                "over_default": 2.0,
                "converged": False,
                "posterior": {"c2": [2.0, 5.0], "y0": [2.05, 1.0]},
            }
        }
    )
    (row,) = every_law.compare(base, new)
    assert row["law"] == "quadratic" and row["recording"] == "run"
    assert row["base_over_default"] == 6.0 and row["new_over_default"] == 2.0
    assert row["base_converged"] is True and row["new_converged"] is False
    assert row["largest_shift_sd"] == pytest.approx(2.0)  # c2: 1.0 / 0.5, not / 5.0


def test_a_law_in_one_result_only_is_left_out_and_a_point_mass_that_moved_is_inf(every_law):
    base = _results(
        {
            "power": {"posterior": {"alpha": [1.0, 0.0]}},
            "viscous": {"posterior": {"zeta": [0.1, 0.01]}},
        }
    )
    new = _results({"power": {"posterior": {"alpha": [1.5, 0.0]}}})
    (row,) = every_law.compare(base, new)
    assert row["law"] == "power" and math.isinf(row["largest_shift_sd"])
