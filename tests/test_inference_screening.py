"""Screening in ``law="auto"``: laws too far behind the best at their optimum are not
sampled (:func:`bayestribo.inference.screening.screen`), on stubs of the fits."""

from __future__ import annotations

import argparse

import numpy as np
import pytest
from _comparison_stubs import N, lpd_shifted, stub_fits, stub_prepared

from bayestribo.inference import comparison
from bayestribo.inference.choice import SMALL_ELPD_DIFFERENCE
from bayestribo.inference.comparison import compare_prepared
from bayestribo.inference.screening import (
    SCREEN_FACTOR,
    optimum_elpd,
    screen,
    screened_by_reduction,
    turning_point_misfit,
)
from bayestribo.inference.settling import FACTOR


def test_a_law_within_the_margin_is_kept_and_one_beyond_it_is_screened_out():
    pointwise = {
        "best": lpd_shifted(0.0),
        "close": lpd_shifted(3.0 * SMALL_ELPD_DIFFERENCE - 1.0),
        "far": lpd_shifted(3.0 * SMALL_ELPD_DIFFERENCE + 3.0),
        "broken": np.full(N, np.nan),
    }
    out = screen(pointwise, dict.fromkeys(pointwise, 2))
    assert out["best"]["elpd_diff"] == 0.0 and not out["best"]["screened"]
    assert not out["close"]["screened"]
    assert out["far"]["screened"] and out["far"]["limit"] == SCREEN_FACTOR * SMALL_ELPD_DIFFERENCE
    assert out["broken"]["screened"]
    assert {row["best"] for row in out.values()} == {"best"}


def test_the_margin_grows_with_the_sd_of_the_difference_and_counts_parameters():
    # a difference of 30 with pointwise scatter: its dse is about sqrt(N) * 0.5 = 7,
    # so the limit 3 * 2 * dse = 42 keeps it
    pointwise = {"a": lpd_shifted(0.0), "b": lpd_shifted(30.0, spread=0.5, seed=1)}
    out = screen(pointwise, {"a": 2, "b": 2})
    assert out["b"]["dse"] == pytest.approx(np.sqrt(N) * np.std(pointwise["b"]), rel=1e-12)
    assert not out["b"]["screened"] and out["b"]["limit"] > 30.0
    # one parameter costs one unit of elpd: equal fits, the simpler is best
    same = {"simple": lpd_shifted(0.0), "rich": lpd_shifted(0.0)}
    ranked = screen(same, {"simple": 1, "rich": 4})
    assert ranked["rich"]["best"] == "simple" and ranked["rich"]["elpd_diff"] == 3.0
    assert optimum_elpd(np.zeros(3), 2) == -2.0


@pytest.mark.filterwarnings("ignore")
def test_only_the_laws_that_can_still_win_are_sampled(monkeypatch):
    shifts = {"viscous": 5000.0, "coulomb": 2.0, "viscous+coulomb": 0.0, "quadratic": 900.0}
    sampled = stub_fits(monkeypatch, shifts)
    lines: list[str] = []
    prepared = stub_prepared()
    c, runs = compare_prepared(prepared, list(shifts), seed=1, rivals=False, progress=lines.append)
    assert sorted(sampled) == ["coulomb", "viscous+coulomb"] == sorted(runs)
    assert c.screened == ["viscous", "quadratic"]
    for law in c.screened:
        row = c.table[law]
        assert row["screened"] and row["sampled"] is False and row["converged"] is None
        assert row["screen"]["elpd_diff"] > row["screen"]["limit"]
    # the verdict among the laws sampled: coulomb is as good and simpler
    assert c.verdict == "coulomb" and set(c.as_good) == {"coulomb", "viscous+coulomb"}
    assert "too far behind the best to win (screened)" in c.describe()
    assert "viscous, quadratic" in c.describe()
    # a line per law at its optimum, one for the screening, one per law sampled
    assert sum("optimum found" in line for line in lines) == 4
    assert sum(line.startswith("sampling") for line in lines) == 2
    assert any("cannot win" in line for line in lines)


@pytest.mark.filterwarnings("ignore")
def test_one_law_left_after_screening_is_the_verdict(monkeypatch):
    shifts = {"viscous": 5000.0, "viscous+coulomb": 0.0}
    sampled = stub_fits(monkeypatch, shifts)
    c, _ = compare_prepared(stub_prepared(), list(shifts), seed=1, rivals=False)
    assert sampled == ["viscous+coulomb"] and c.verdict == "viscous+coulomb"
    assert c.table["viscous+coulomb"]["elpd_diff"] == 0.0
    # without screening every law is sampled
    sampled.clear()
    compare_prepared(stub_prepared(), list(shifts), seed=1, rivals=False, screening=False)
    assert sampled == ["viscous", "viscous+coulomb"]


def test_a_law_whose_dissipation_cannot_follow_the_turning_points_is_judged_so():
    # ΔE(A) of viscous damping and Coulomb friction, known to 0.1 %
    amp = np.linspace(1.0, 10.0, 12)
    mean = 4 * 0.03 * amp + 2 * np.pi * 0.02 * amp**2
    sd = 1e-3 * mean
    chi2 = {
        law: turning_point_misfit(law, amp, mean, sd, 10.0)
        for law in ("viscous+coulomb", "coulomb+hysteretic", "coulomb+quadratic", "power")
    }
    assert chi2["viscous+coulomb"] < 1e-6 and chi2["coulomb+hysteretic"] < 1e-6
    assert chi2["coulomb+quadratic"] > 1e4 and chi2["power"] > 1e4


def _args(**kw) -> argparse.Namespace:
    return argparse.Namespace(**{"law": "auto", "quiet": False, "json": False, **kw})


def test_the_progress_line_is_for_a_terminal_only(monkeypatch, capsys):
    from bayestribo.cli.fit import law_progress

    monkeypatch.setattr("sys.stderr.isatty", lambda: True)
    say = law_progress(_args())
    assert say is not None
    say("law 1/12 viscous: optimum found (0.1 s)")
    assert capsys.readouterr().err == (
        "bayestribo fit --law auto: law 1/12 viscous: optimum found (0.1 s)\n"
    )
    assert law_progress(_args(quiet=True)) is None
    assert law_progress(_args(json=True)) is None
    assert law_progress(_args(law="viscous+coulomb")) is None
    monkeypatch.setattr("sys.stderr.isatty", lambda: False)
    assert law_progress(_args()) is None


def test_fit_takes_quiet():
    from bayestribo.cli.main import build_parser

    args = build_parser().parse_args(["fit", "run.csv", "--law", "auto", "--quiet"])
    assert args.quiet and args.law == "auto"


def _row(diff: float, dse: float, screened: bool = False) -> dict:
    return {"elpd_diff": diff, "dse": dse, "screened": screened, "stage": "optimum"}


def test_a_law_that_is_a_screened_law_at_its_optimum_goes_with_it():
    # far behind (a difference of 4.3 dse: kept by the screen's limit of 6 dse) and
    # its extra term at zero: the nested law screened out stands for it
    screens = {
        "viscous": _row(3.2e9, 5.2e8, screened=True),
        "viscous+quadratic": _row(3.3e9, 7.7e8),
        "viscous+quadratic+x": _row(3.4e9, 7.8e8),
        "close": _row(40.0, 25.0),
        "own": _row(3.0e9, 5.0e8),
        "best": _row(0.0, 0.0),
    }
    asked: list[tuple[str, list[str]]] = []

    def reduces(law, laws):
        asked.append((law, laws))
        if law == "own":
            return None
        return (laws[-1], ["quadratic"]) if laws else None

    out = screened_by_reduction(list(screens), screens, reduces)
    assert sorted(out) == ["viscous+quadratic", "viscous+quadratic+x"]
    row = out["viscous+quadratic"]
    assert row["screened"] and row["stage"] == "reduction"
    assert row["reduces_to"] == "viscous" and row["terms_at_zero"] == ["quadratic"]
    assert row["elpd_diff"] == screens["viscous+quadratic"]["elpd_diff"]
    # a law screened out this way counts for the laws after it
    assert out["viscous+quadratic+x"]["reduces_to"] == "viscous+quadratic"
    # within the tie rule's reach of the best (40 < 2 x 25) or at the best: never asked
    assert [law for law, _ in asked] == ["viscous+quadratic", "viscous+quadratic+x", "own"]
    assert not screens["viscous+quadratic"]["screened"]  # the screen's rows are kept


def test_a_law_not_clearly_behind_the_best_is_not_screened_by_reduction():
    # the tie rule's reach is max(4, 2 dse); clearly behind: beyond it by a third
    clear = 1.0 + 1.0 / FACTOR
    screens = {
        "a": _row(300.0, 1.0, screened=True),
        "at the reach": _row(SMALL_ELPD_DIFFERENCE, 0.1),
        "past it by less than a third": _row(2.0 * 10.0 * clear - 0.5, 10.0),
        "clearly behind": _row(2.0 * 10.0 * clear + 0.5, 10.0),
        "small reach, clearly behind": _row(SMALL_ELPD_DIFFERENCE * clear + 0.1, 0.1),
    }
    out = screened_by_reduction(list(screens), screens, lambda law, laws: ("a", ["t"]))
    assert sorted(out) == ["clearly behind", "small reach, clearly behind"]


@pytest.mark.filterwarnings("ignore")
def test_a_law_that_reduces_to_a_screened_law_is_not_sampled(monkeypatch):
    # viscous+quadratic is behind by 2000 with a dse of 400 at its optimum (5 dse: kept
    # by the screen), and at its optimum it is viscous, which is screened out
    shifts = {"viscous": 5000.0, "viscous+quadratic": 2000.0, "viscous+coulomb": 0.0}
    spread = {"viscous+quadratic": 400.0 / np.sqrt(N), "viscous+coulomb": 0.0}
    sampled = stub_fits(monkeypatch, shifts, spread=spread)
    calls: list[tuple[str, list[str]]] = []

    def among(law, posterior, theta, laws, optima):
        calls.append((law, list(laws)))
        return ("viscous", ["quadratic"]) if law == "viscous+quadratic" else None

    monkeypatch.setattr(comparison, "reduction_among", among)
    lines: list[str] = []
    c, runs = compare_prepared(
        stub_prepared(), list(shifts), seed=1, rivals=False, progress=lines.append
    )
    assert sampled == ["viscous+coulomb"] == list(runs)
    # asked at each optimum of the laws it nests (whose second pass may wait), then by
    # the screen
    at_optima = [("viscous+quadratic", ["viscous"]), ("viscous+coulomb", ["viscous"])]
    assert calls == [*at_optima, ("viscous+quadratic", ["viscous"])]
    assert c.screened == ["viscous", "viscous+quadratic"]
    row = c.table["viscous+quadratic"]
    assert row["screened"] and row["sampled"] is False and row["converged"] is None
    assert row["screen"]["stage"] == "reduction" and row["screen"]["reduces_to"] == "viscous"
    assert row["screen"]["elpd_diff"] < row["screen"]["limit"]  # kept by the screen alone
    assert "viscous+quadratic" not in c.equivalent
    assert c.verdict == "viscous+coulomb"
    assert any("cannot win" in line and "viscous+quadratic" in line for line in lines)


@pytest.mark.filterwarnings("ignore")
def test_without_screening_a_law_that_reduces_to_a_far_law_is_sampled(monkeypatch):
    shifts = {"viscous": 5000.0, "viscous+quadratic": 2000.0, "viscous+coulomb": 0.0}
    sampled = stub_fits(monkeypatch, shifts)
    monkeypatch.setattr(comparison, "reduction_among", lambda *args: ("viscous", ["quadratic"]))
    c, _ = compare_prepared(stub_prepared(), list(shifts), seed=1, rivals=False, screening=False)
    assert sorted(sampled) == sorted(shifts) and c.screened == []


@pytest.mark.filterwarnings("ignore")
def test_a_law_with_as_many_parameters_as_increments_is_screened_out_and_named(monkeypatch):
    # 3 increments: viscous (1 stub parameter) and coulomb (2) are sampled; viscous+coulomb
    # and coulomb+hysteretic (3 each) are not identified by them: not sampled, their rows
    # say why, and the comparison's text names them apart from laws too far behind
    shifts = {"viscous": 0.0, "coulomb": 1.0, "viscous+coulomb": 0.0, "coulomb+hysteretic": 0.0}
    sampled = stub_fits(monkeypatch, shifts)
    lines: list[str] = []
    c, runs = compare_prepared(
        stub_prepared(3), list(shifts), seed=1, rivals=False, progress=lines.append
    )
    assert sorted(sampled) == ["coulomb", "viscous"] == sorted(runs)
    assert c.screened == ["viscous+coulomb", "coulomb+hysteretic"]
    for law in c.screened:
        row = c.table[law]
        assert row["sampled"] is False and row["screen"]["stage"] == "increments"
        assert "3 increments" in row["screen"]["reason"] and "adequate" in row
    text = c.describe()
    assert "2 not sampled, with as many parameters as the record has increments" in text
    assert "too far behind" not in text
    assert any("3 increments, which do not identify them" in line for line in lines)


@pytest.mark.filterwarnings("ignore")
def test_laws_all_outnumbered_are_all_sampled(monkeypatch):
    # with 1 increment every law has as many parameters: none is left out for it
    shifts = {"viscous": 0.0, "coulomb": 1.0}
    sampled = stub_fits(monkeypatch, shifts)
    c, _ = compare_prepared(stub_prepared(1), list(shifts), seed=1, rivals=False)
    assert sorted(sampled) == ["coulomb", "viscous"] and c.screened == []
