"""A count before its noun agrees with it: "1 run", "2 runs" (bayestribo._plural)."""

from __future__ import annotations

import pytest

from bayestribo._plural import count
from bayestribo.reports import kit


@pytest.mark.parametrize(
    ("n", "noun", "plural", "said"),
    [
        (1, "run", None, "1 run"),
        (2, "run", None, "2 runs"),
        (0, "file", None, "0 files"),
        (1, "half cycle", None, "1 half cycle"),
        (5, "half cycle", None, "5 half cycles"),
        (1, "analysis", "analyses", "1 analysis"),
        (3, "analysis", "analyses", "3 analyses"),
    ],
)
def test_a_count_takes_the_singular_for_one_and_the_plural_otherwise(n, noun, plural, said):
    assert count(n, noun, plural) == said


def test_the_reports_count_as_the_command_line_does():
    assert kit.count is count


def test_a_campaigns_text_counts_one_run_in_the_singular():
    from types import SimpleNamespace

    from bayestribo.cli.campaign import _text

    row = {
        "kind": "contact", "group": "load_N=0.3", "n_runs": 1, "parameter": "zeta",
        "mean_median": 0.02, "mean_low": 0.019, "mean_high": 0.021, "sigma_median": 0.001,
        "sigma_low": 0.0, "sigma_high": 0.002, "converged": True,
    }  # fmt: skip
    analysis = SimpleNamespace(
        laws={"viscous+coulomb": ["a"], "viscous+quadratic": ["b", "c"]},
        group_rows=lambda: [row],
        trend_rows=lambda: [],
        prob=0.95,
        quantities={},
        left_out={},
        derived=[],
        zeta0=None,
        excluded=[],
        converged=True,
        runs=[],
    )
    text = _text(analysis, [], None)
    assert "viscous+coulomb (1 run)" in text and "viscous+quadratic (2 runs)" in text
    assert ", 1 run\n" in text + "\n" and "1 runs" not in text
