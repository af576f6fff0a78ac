"""The rivals' comparison on the finer grid starts each law's optimiser at its optimum
on the first grid (inference/comparison.py, module notes: Rivals)."""

from __future__ import annotations

import numpy as np
import pytest

from bayestribo.inference import comparison, prepare
from bayestribo.inference.preparation import regrid


@pytest.fixture(scope="module")
def grids(bundled_run):
    """The bundled run on its half-cycle grid and on the rivals' finer grid."""
    prepared = prepare(bundled_run, seed=1)
    fine = regrid(prepared, comparison.TIE_GRID * int(prepared.data.increments.size))
    return prepared, fine


def test_a_law_started_at_its_first_grid_optimum_finds_the_multistarts_optimum(grids, monkeypatch):
    prepared, fine = grids
    law = "viscous+coulomb"
    first = comparison._optimise(law, prepared, "exact", False, {})
    searched = comparison._optimise(law, fine, "exact", False, {})
    start = dict(zip(first.posterior.names, first.optimum[0], strict=True))

    def no_multistart(*args, **kwargs):
        raise AssertionError("the optimiser ran from the first guesses")

    monkeypatch.setattr(comparison, "find_optimum", no_multistart)
    started = comparison._optimise(law, fine, "exact", False, {}, start=start)
    # the same optimum on both passes (within the optimiser's reach, 0.5 of log density)
    for a, b, post in (
        (started.optimum[0], searched.optimum[0], started.posterior),
        (started.second_optimum[0], searched.second_optimum[0], started.second),
    ):
        lp = post(np.vstack([a, b]))
        assert np.all(np.isfinite(lp)) and abs(lp[0] - lp[1]) < 0.5
    # and the screening's estimate there
    assert abs(np.sum(started.pointwise) - np.sum(searched.pointwise)) < 0.5


def test_a_start_that_lacks_a_coordinate_is_not_used(grids, monkeypatch):
    _, fine = grids
    called = []
    real = comparison.find_optimum

    def counted(*args, **kwargs):
        called.append(True)
        return real(*args, **kwargs)

    monkeypatch.setattr(comparison, "find_optimum", counted)
    comparison._optimise("viscous+coulomb", fine, "exact", False, {}, start={"zeta": 0.01})
    assert called  # the first guesses, not a partial start


def test_the_rivals_are_compared_from_their_first_grid_optima(grids, monkeypatch):
    prepared, fine = grids
    seen = {}

    def compare(fine, laws, **kwargs):
        seen.update(kwargs, laws=laws, points=int(fine.data.increments.size))
        raise comparison.BayestriboError("stop here")

    monkeypatch.setattr(comparison, "compare_prepared", compare)
    # the laws sampled on the finer grid (not judged at their optima there alone)
    monkeypatch.setattr(comparison, "_judged_at_optimum", lambda *args: None)
    starts = {"viscous+coulomb": {"zeta": 0.01}, "coulomb+hysteretic": {"mu_k": 0.1}}
    out = comparison._compare_rivals(
        prepared,
        ["viscous+coulomb", "coulomb+hysteretic"],
        1,
        "exact",
        comparison.SamplerSettings(),
        False,
        starts=starts,
    )
    assert seen["starts"] is starts and seen["rivals"] is False
    assert seen["points"] == int(fine.data.increments.size)
    assert out["decided"] is False and out["error"] == "stop here"
