"""One law per group of repeats, from the runs' law comparisons (campaign/laws.py)."""

from __future__ import annotations

import pytest

from bayestribo.campaign.laws import choose_group_law, comparison_digest, group_laws
from bayestribo.inference.choice import SMALL_ELPD_DIFFERENCE


def _comparison(verdict: str, rows: dict[str, tuple], equivalent: dict | None = None) -> dict:
    """A run's comparison as ``LawComparison.to_dict`` gives it: per law (elpd, dse,
    adequate), or a string naming the nested law it reduced to."""
    table = {}
    for law, row in rows.items():
        if isinstance(row, str):
            table[law] = {"sampled": False, "reduces_to": row, "adequate": True}
        else:
            elpd, dse, adequate = row
            table[law] = {"elpd_loo": elpd, "dse": dse, "adequate": adequate, "sampled": True}
    return {
        "verdict": verdict,
        "best": verdict,
        "adequate": True,
        "equivalent": equivalent or {},
        "table": table,
    }


def test_the_group_law_is_the_best_summed_elpd_and_the_runs_that_differ_are_named():
    # two runs prefer viscous+quadratic by a little each; one prefers coulomb+power by a
    # little: together viscous+quadratic is clearly best (30 units ahead)
    a = _comparison(
        "viscous+quadratic", {"viscous+quadratic": (100, 0, True), "coulomb+power": (80, 3, True)}
    )
    b = _comparison(
        "viscous+quadratic", {"viscous+quadratic": (100, 0, True), "coulomb+power": (85, 3, True)}
    )
    c = _comparison(
        "coulomb+power", {"viscous+quadratic": (95, 2, True), "coulomb+power": (100, 0, True)}
    )
    got = choose_group_law("oil", {"r1": a, "r2": b, "r3": c})
    assert got.law == got.best == "viscous+quadratic" and got.decided and got.adequate
    assert got.disagree == ("r3",) and got.verdicts["r3"] == "coulomb+power"
    row = got.table["coulomb+power"]
    assert row["elpd"] == 265 and row["elpd_diff"] == 30
    # independent dse combined in quadrature over runs: √(9 + 9 + 4)
    assert row["dse"] == pytest.approx((9 + 9 + 4) ** 0.5)


def test_the_simplest_law_within_the_noise_of_the_best_is_kept():
    rows = {"viscous": (100, 2, True), "viscous+quadratic": (101, 0, True)}
    got = choose_group_law(
        "g", {"r1": _comparison("viscous", rows), "r2": _comparison("viscous", rows)}
    )
    assert got.best == "viscous+quadratic"
    assert got.table["viscous"]["elpd_diff"] == 2 < SMALL_ELPD_DIFFERENCE
    assert got.law == "viscous" and got.disagree == ()


def test_a_law_that_reduced_to_a_nested_one_counts_with_the_nested_elpd():
    a = _comparison("viscous", {"viscous": (50, 0, True), "viscous+quadratic": "viscous"})
    b = _comparison("viscous", {"viscous": (60, 0, True), "viscous+quadratic": (61, 1, True)})
    got = choose_group_law("g", {"r1": a, "r2": b})
    assert got.table["viscous+quadratic"]["elpd"] == 111
    assert got.law == "viscous"  # one unit better, two more parameters


def test_a_law_left_out_by_one_run_cannot_be_the_group_law():
    a = _comparison("coulomb", {"coulomb": (10, 0, True), "viscous+coulomb": (500, 0, True)})
    b = _comparison("coulomb", {"coulomb": (10, 0, True)})  # viscous+coulomb screened out
    got = choose_group_law("g", {"r1": a, "r2": b})
    assert set(got.table) == {"coulomb"} and got.law == "coulomb"


def test_a_law_that_misfits_a_run_gives_way_to_one_that_holds_in_every_run():
    rows = {"viscous": (100, 0, False), "viscous+coulomb": (99, 1, True)}
    got = choose_group_law(
        "g",
        {"r1": _comparison("viscous+coulomb", rows), "r2": _comparison("viscous+coulomb", rows)},
    )
    assert got.best == "viscous" and got.law == "viscous+coulomb" and got.adequate
    nothing_holds = {"viscous": (100, 0, False), "viscous+coulomb": (99, 1, False)}
    got = choose_group_law("g", {"r1": _comparison("viscous", nothing_holds)})
    assert got.law == "viscous" and not got.adequate


def test_without_a_law_compared_in_every_run_the_most_runs_verdict_is_kept_and_said():
    a = _comparison("viscous", {"viscous": (1, 0, True)})
    b = _comparison("coulomb", {"coulomb": (1, 0, True)})
    c = _comparison("viscous", {"viscous": (1, 0, True)})
    got = choose_group_law("g", {"r1": a, "r2": comparison_digest(b), "r3": c})
    assert not got.decided and got.law == "viscous" and got.disagree == ("r2",)
    # runs fitted in one law (no comparison): their law is their verdict
    got = choose_group_law("g", {"r1": None, "r2": None}, {"r1": "viscous", "r2": "viscous"})
    assert not got.decided and got.law == "viscous" and got.disagree == ()


class _Fit:
    def __init__(self, name: str, load: float, comparison: dict) -> None:
        self.metadata = {"run_id": name, "lubricant": "oil", "load_N": load}
        self.law = comparison["verdict"]
        self.law_comparison = comparison


def test_every_group_of_repeats_has_its_own_law():
    quad = {"viscous": (0, 30, False), "viscous+quadratic": (100, 0, True)}
    visc = {"viscous": (100, 0, True), "viscous+quadratic": (100.5, 0.5, True)}
    fits = [
        _Fit("a1", 0.1, _comparison("viscous+quadratic", quad)),
        _Fit("a2", 0.1, _comparison("viscous+quadratic", quad)),
        _Fit("b1", 0.3, _comparison("viscous", visc)),
        _Fit("b2", 0.3, _comparison("viscous+quadratic", visc)),
    ]
    groups, law_of_run = group_laws(fits, ("lubricant", "water_mass_fraction", "load_N"))
    assert set(groups) == {"lubricant=oil,load_N=0.1", "lubricant=oil,load_N=0.3"}
    assert law_of_run == {
        "a1": "viscous+quadratic",
        "a2": "viscous+quadratic",
        "b1": "viscous",
        "b2": "viscous",
    }
    assert groups["lubricant=oil,load_N=0.3"].disagree == ("b2",)


def test_a_law_settled_at_its_optimum_counts_with_its_estimate_there():
    a = _comparison("viscous", {"viscous": (50, 0, True), "coulomb": (48, 1, True)})
    b = _comparison("viscous", {"viscous": (60, 0, True)})
    b["table"]["coulomb"] = {
        "sampled": False,
        "settled": True,
        "adequate": True,
        "settle": {"best": "viscous", "elpd_diff": 1.5, "dse": 0.5, "as_good": True},
    }
    for digest in (None, comparison_digest):
        runs = {"r1": a, "r2": digest(b) if digest else b}
        got = choose_group_law("g", runs)
        assert got.table["coulomb"]["elpd"] == 48 + 58.5
        assert got.law == "viscous"
    # a settled row without its best's elpd is left out, as a screened one is
    del b["table"]["viscous"]["elpd_loo"]
    assert "coulomb" not in choose_group_law("g", {"r1": a, "r2": b}).table
