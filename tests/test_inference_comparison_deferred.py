"""A law whose optimum is a law it nests has its second pass made only when it is judged
on its own (:class:`bayestribo.inference.screening.LawOptimum`), on stubs of the fits."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from _comparison_stubs import N, _Posterior, lpd_shifted, stub_fits, stub_prepared

from bayestribo.inference import comparison
from bayestribo.inference.choice import law_of
from bayestribo.inference.comparison import compare_prepared
from bayestribo.inference.screening import LawOptimum


def _lazy_optima(monkeypatch, shifts: dict[str, float], spread: dict[str, float]) -> list[str]:
    """Stub the optimiser with a second pass made when first asked for; returns the
    list of the laws whose second pass was made."""
    made: list[str] = []

    def optimise(law, prepared, model, discrepancy, optima, start=None):
        post = _Posterior(law_of(law).parameter_names)
        post.law = law
        theta = np.zeros(len(post.names))
        opt = (theta, np.eye(len(theta)), None)

        def finish():
            made.append(law)
            return post, opt, lpd_shifted(shifts[law], spread.get(law, 0.01), 2)

        return LawOptimum(law, post, opt, finish=finish)

    monkeypatch.setattr(comparison, "_optimise", optimise)
    return made


def _reduces_to_viscous(monkeypatch) -> None:
    """viscous+quadratic is viscous at its optimum (first pass), wherever viscous is."""

    def among(law, posterior, theta, laws, optima):
        return (
            ("viscous", ["quadratic"]) if law == "viscous+quadratic" and "viscous" in laws else None
        )

    def reduction(law, posterior, theta, fitted, optima):
        return among(law, posterior, theta, list(fitted), optima)

    monkeypatch.setattr(comparison, "reduction_among", among)
    monkeypatch.setattr(comparison, "reduction", reduction)


def test_a_second_pass_given_as_a_function_is_made_once_when_first_asked_for():
    calls: list[int] = []
    post = SimpleNamespace(names=["a", "b"])
    opt = (np.zeros(2), np.eye(2), None)

    def finish():
        calls.append(1)
        return post, opt, np.ones(3)

    at = LawOptimum("x", post, opt, finish=finish)
    assert at.pending and at.n_parameters == 2 and not calls
    assert at.second is post and at.second_optimum is opt and at.pointwise.sum() == 3.0
    assert calls == [1] and not at.pending
    with pytest.raises(ValueError):
        LawOptimum("x", post, opt)


@pytest.mark.filterwarnings("ignore")
def test_a_law_that_reduces_to_a_sampled_law_never_has_its_second_pass_made(monkeypatch):
    shifts = {"viscous": 0.0, "viscous+quadratic": 1.0, "coulomb": 5000.0}
    sampled = stub_fits(monkeypatch, shifts)
    made = _lazy_optima(monkeypatch, shifts, {})
    _reduces_to_viscous(monkeypatch)
    lines: list[str] = []
    c, runs = compare_prepared(
        stub_prepared(), list(shifts), seed=1, rivals=False, progress=lines.append
    )
    assert sampled == ["viscous"] == list(runs)
    assert sorted(made) == ["coulomb", "viscous"]
    assert c.table["viscous+quadratic"]["reduces_to"] == "viscous"
    assert c.equivalent == {"viscous+quadratic": "viscous"}
    assert c.screened == ["coulomb"] and c.verdict == "viscous"
    assert any("viscous+quadratic" in line and "reduces to viscous" in line for line in lines)


@pytest.mark.filterwarnings("ignore")
def test_a_law_that_is_a_screened_law_at_its_optimum_is_screened_as_before(monkeypatch):
    # viscous is screened out; viscous+quadratic, viscous at its optimum, 5 dse behind
    # the best: its second pass is made, and the screen with it screens it by reduction
    shifts = {"viscous": 5000.0, "viscous+quadratic": 2000.0, "viscous+coulomb": 0.0}
    spread = {"viscous+quadratic": 400.0 / np.sqrt(N), "viscous+coulomb": 0.0}
    sampled = stub_fits(monkeypatch, shifts, spread=spread)
    made = _lazy_optima(monkeypatch, shifts, spread)
    _reduces_to_viscous(monkeypatch)
    c, runs = compare_prepared(stub_prepared(), list(shifts), seed=1, rivals=False)
    assert sampled == ["viscous+coulomb"] == list(runs)
    assert sorted(made) == sorted(shifts)
    assert c.screened == ["viscous", "viscous+quadratic"]
    row = c.table["viscous+quadratic"]["screen"]
    assert row["stage"] == "reduction" and row["reduces_to"] == "viscous"
    assert c.verdict == "viscous+coulomb"
