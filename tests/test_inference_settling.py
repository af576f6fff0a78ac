"""Settling in ``law="auto"``: a law that misfits at its optimum and can no longer change
the choice is not sampled (:func:`bayestribo.inference.settling.settle`), on stubs of
the fits."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from _comparison_stubs import N, lpd_shifted, stub_fits, stub_prepared

from bayestribo.inference import comparison
from bayestribo.inference.choice import SMALL_ELPD_DIFFERENCE
from bayestribo.inference.comparison import compare_prepared
from bayestribo.inference.records import LawComparison
from bayestribo.inference.settling import FACTOR, settle

REACH = SMALL_ELPD_DIFFERENCE


def _settle(shift: float, *, verdict_shift: float = 0.0, **kw) -> dict:
    kw = {"verdict_adequate": False, "loses_tie": True, "small": REACH, **kw}
    return settle(
        (lpd_shifted(shift), 2), (lpd_shifted(verdict_shift), 2), (lpd_shifted(0.0), 2), **kw
    )


def test_a_law_clearly_as_good_or_clearly_behind_is_settled_and_one_near_the_edge_is_not():
    inside = _settle(REACH * (1 - 1 / FACTOR) - 0.1)
    assert inside["settled"] and inside["as_good"] is True
    behind = _settle(REACH * (1 + 1 / FACTOR) + 0.1)
    assert behind["settled"] and behind["as_good"] is False
    for edge in (REACH * (1 - 1 / FACTOR) + 0.1, REACH, REACH * (1 + 1 / FACTOR) - 0.1):
        out = _settle(edge)
        assert out["as_good"] is None and not out["settled"]
    assert inside["reach"] == REACH and inside["elpd_diff"] == pytest.approx(
        REACH * (1 - 1 / FACTOR) - 0.1
    )


def test_a_law_that_could_become_the_best_or_push_the_verdict_out_is_sampled():
    # ahead of the best by more than a third of the reach
    assert not _settle(-REACH / FACTOR - 0.1)["settled"]
    assert _settle(-REACH / FACTOR + 0.1)["settled"]
    # the verdict a whole reach behind the best: a law as good as the best would push it out
    pushed = _settle(0.0, verdict_shift=REACH)
    assert pushed["verdict_gain"] == pytest.approx(REACH) and not pushed["settled"]
    assert not _settle(float("inf"))["settled"]


def test_a_law_that_could_be_chosen_is_sampled():
    # no law adequate: a simpler law as good as the best would be the verdict
    assert not _settle(0.5, loses_tie=False)["settled"]
    # unless the verdict is adequate, or the law is clearly behind
    assert _settle(0.5, loses_tie=False, verdict_adequate=True)["settled"]
    assert _settle(REACH * 2, loses_tie=False)["settled"]


def _compare(shifts, adequate=(), screening=True, lines=None):
    return compare_prepared(
        stub_prepared(),
        list(shifts),
        seed=1,
        rivals=False,
        screening=screening,
        progress=(lines.append if lines is not None else None),
    )


@pytest.mark.filterwarnings("ignore")
def test_misfitting_laws_that_cannot_change_the_choice_are_settled(monkeypatch):
    # none adequate: viscous (simplest) is the verdict; coulomb and viscous+coulomb
    # cannot change that, one as good and one behind
    shifts = {"viscous": 0.0, "coulomb": 1.0, "viscous+coulomb": 9.0}
    sampled = stub_fits(monkeypatch, shifts, adequate=set())
    lines: list[str] = []
    c, runs = _compare(shifts, lines=lines)
    assert sampled == ["viscous"] == list(runs)
    assert c.verdict == "viscous" and c.settled == ["coulomb", "viscous+coulomb"]
    assert c.as_good == ["viscous", "coulomb"]
    for law in c.settled:
        row = c.table[law]
        assert row["settled"] and row["sampled"] is False and row["converged"] is None
        assert "elpd_loo" not in row
    assert c.table["coulomb"]["settle"]["as_good"] is True
    assert c.table["viscous+coulomb"]["settle"]["as_good"] is False
    assert "(settled): coulomb, viscous+coulomb" in c.describe()
    assert sum("cannot change the choice" in line for line in lines) == 2
    assert LawComparison.from_dict(c.to_dict()).settled == c.settled
    # the same choice as the comparison that samples every law
    sampled.clear()
    full, _ = _compare(shifts, screening=False)
    assert sampled == list(shifts)
    assert (full.verdict, full.as_good) == (c.verdict, c.as_good)


def _smallest_first(monkeypatch) -> None:
    # the laws sampled in the order given (smallest first), not the predicted verdict
    # first: the settling of a law sampled later than a provisional verdict
    monkeypatch.setattr(comparison, "sampling_order", lambda laws, *args, **kwargs: list(laws))


@pytest.mark.filterwarnings("ignore")
def test_an_adequate_law_or_one_ahead_of_the_verdict_is_sampled(monkeypatch):
    # coulomb holds (it may be the verdict); viscous+coulomb is ahead of viscous by far
    shifts = {"viscous": 8.0, "coulomb": 9.0, "viscous+coulomb": 0.0}
    sampled = stub_fits(monkeypatch, shifts, adequate={"coulomb"})
    _smallest_first(monkeypatch)
    c, _ = _compare(shifts)
    assert sampled == list(shifts) and c.settled == []
    assert c.verdict == "viscous+coulomb"


@pytest.mark.filterwarnings("ignore")
def test_a_settled_law_is_sampled_when_a_later_law_moves_the_verdict(monkeypatch):
    # none adequate. After viscous, quadratic (as simple, later in order, its pointwise
    # difference scattered: a wide reach) is settled as good; viscous+coulomb then
    # leaves viscous behind, and quadratic, still as good and simpler, could now be the
    # verdict: it is sampled after all
    shifts = {"viscous": 10.0, "quadratic": 10.5, "viscous+coulomb": 0.0}
    sampled = stub_fits(monkeypatch, shifts, adequate=set(), spread={"quadratic": 0.5})
    _smallest_first(monkeypatch)
    lines: list[str] = []
    c, _ = _compare(shifts, lines=lines)
    assert sampled == ["viscous", "viscous+coulomb", "quadratic"]
    assert any("quadratic: the verdict moved; sampled after all" in line for line in lines)
    assert c.settled == [] and c.table["quadratic"]["sampled"] is True
    assert c.verdict == "quadratic" and "viscous" not in c.as_good
    sampled.clear()
    full, _ = _compare(shifts, screening=False)
    assert (full.verdict, full.as_good) == (c.verdict, c.as_good)


def test_an_adequate_law_is_settled_only_where_it_cannot_be_chosen():
    # the rivals' comparison: an adequate law as good as the best but more complex than
    # an adequate verdict cannot be chosen; with the verdict misfitting it would be
    assert _settle(0.5, adequate=True, verdict_adequate=True)["settled"]
    assert not _settle(0.5, adequate=True, verdict_adequate=False)["settled"]
    assert not _settle(0.5, adequate=True, verdict_adequate=True, loses_tie=False)["settled"]
    assert _settle(REACH * 2, adequate=True, loses_tie=False)["settled"]


@pytest.mark.filterwarnings("ignore")
def test_adequate_laws_are_settled_in_the_rivals_comparison_alone(monkeypatch):
    shifts = {"viscous+coulomb": 0.0, "coulomb+power": 1.0}
    sampled = stub_fits(monkeypatch, shifts, adequate=set(shifts))
    c, _ = _compare(shifts)
    assert sampled == list(shifts) and c.settled == []
    sampled.clear()
    c, _ = compare_prepared(
        stub_prepared(), list(shifts), seed=1, rivals=False, settle_adequate=True
    )
    assert sampled == ["viscous+coulomb"] and c.settled == ["coulomb+power"]
    assert c.verdict == "viscous+coulomb" and c.as_good == list(shifts)


@pytest.mark.filterwarnings("ignore")
def test_the_rivals_comparison_has_its_progress_line(monkeypatch):
    shifts = {"viscous+coulomb": 0.0, "coulomb+hysteretic": 0.5}
    stub_fits(monkeypatch, shifts, adequate=set(shifts))
    asked: list[list[str]] = []

    def rivals(prepared, laws, *args, **kwargs):
        asked.append(list(laws))
        return {"laws": list(laws), "decided": False, "per_half_cycle": 4}

    monkeypatch.setattr(comparison, "_compare_rivals", rivals)
    lines: list[str] = []
    compare_prepared(stub_prepared(), list(shifts), seed=1, progress=lines.append)
    assert asked == [list(shifts)]
    assert lines[-1] == (
        "comparing viscous+coulomb with coulomb+hysteretic again on 4 increments per half cycle"
    )


def test_the_halves_check_has_its_progress_line(monkeypatch):
    from bayestribo.inference import auto

    halves = SimpleNamespace(agree=True, to_dict=lambda: {"agree": True})
    monkeypatch.setattr(auto, "law_halves", lambda *args, **kwargs: halves)
    c = LawComparison("stub", {}, "viscous", "viscous", ["viscous"])
    lines: list[str] = []
    checked = auto._check_halves(
        c, None, np.random.default_rng(1), None, "exact", False, lines.append
    )
    assert checked.halves == {"agree": True}
    assert lines == ["fitting viscous to each half of the motion"]
    # a comparison that does not hold is not split, and says nothing
    lines.clear()
    misfit = LawComparison("stub", {}, "viscous", "viscous", ["viscous"], adequate=False)
    auto._check_halves(misfit, None, np.random.default_rng(1), None, "exact", False, lines.append)
    assert lines == []


@pytest.mark.filterwarnings("ignore")
def test_an_adequate_law_clearly_behind_is_settled_and_still_counts_as_holding(monkeypatch):
    # coulomb holds but is far behind the misfitting viscous: its draws would serve
    # nothing, and it still keeps the law-free fit away (no stub answers for "free")
    shifts = {"viscous": 0.0, "coulomb": 9.0}
    sampled = stub_fits(monkeypatch, shifts, adequate={"coulomb"})
    c, _ = compare_prepared(stub_prepared(), list(shifts), seed=1, law_free=True)
    assert sampled == ["viscous"] and c.settled == ["coulomb"]
    assert c.table["coulomb"]["settle"]["as_good"] is False
    assert c.verdict == "viscous" and not c.adequate and c.as_good == ["viscous"]


@pytest.mark.filterwarnings("ignore")
def test_rivals_judged_at_their_optima_on_the_finer_grid_are_not_sampled(monkeypatch):
    shifts = {"viscous": 0.0, "power": 1.0, "coulomb": 30.0}
    adequate = set(shifts)
    sampled = stub_fits(monkeypatch, shifts, adequate=adequate)
    monkeypatch.setattr(comparison, "regrid", lambda prepared, n: prepared)
    fine = SimpleNamespace(name="stub", data=SimpleNamespace(increments=np.zeros(N)))

    def rivals(laws):
        return comparison._compare_rivals(fine, laws, 1, "exact", None, False)

    # every law as good: the finer grid cannot tell them apart
    out = rivals(["viscous", "power"])
    assert sampled == [] and out["settled"] is True and out["decided"] is False
    assert out["as_good"] == ["viscous", "power"] and out["table"]["power"]["elpd_diff"] > 0
    # coulomb clearly behind there: decided, the first verdict kept
    out = rivals(["viscous", "power", "coulomb"])
    assert sampled == [] and out["decided"] is True and out["verdict"] == "viscous"
    assert out["as_good"] == ["viscous", "power"] and out["adequate"] is True
    # a rival near the tie rule's edge, or another verdict there: the laws are sampled
    shifts["power"] = REACH
    out = rivals(["viscous", "power"])
    assert sampled == ["viscous", "power"] and "settled" not in out
    sampled.clear()
    shifts["power"] = 1.0
    adequate.discard("viscous")
    out = rivals(["viscous", "power"])
    assert sampled and "settled" not in out


@pytest.mark.filterwarnings("ignore")
def test_the_verdict_the_optima_predict_is_sampled_first(monkeypatch):
    # smallest first, power is ahead of viscous and coulomb+power ahead of both when
    # their turns come: all three are sampled. The optima predict coulomb+power (the
    # one adequate law): sampled first, the others are settled behind it
    shifts = {"viscous": 11.0, "power": 8.0, "coulomb+power": 0.0}
    sampled = stub_fits(monkeypatch, shifts, adequate={"coulomb+power"})
    lines: list[str] = []
    c, _ = _compare(shifts, lines=lines)
    assert sampled == ["coulomb+power"] and c.settled == ["viscous", "power"]
    assert lines.index("sampling coulomb+power (1/3)") < min(
        i for i, line in enumerate(lines) if "cannot change the choice" in line
    )
    sampled.clear()
    _smallest_first(monkeypatch)
    smallest, _ = _compare(shifts)
    assert sampled == list(shifts) and smallest.settled == []
    assert (smallest.verdict, smallest.as_good) == (c.verdict, c.as_good)
    assert c.verdict == "coulomb+power" and c.as_good == ["coulomb+power"]


def test_sampling_order_puts_the_simplest_adequate_law_as_good_as_the_best_first():
    from bayestribo.inference.settling import sampling_order

    laws = ["viscous", "coulomb", "power", "viscous+coulomb"]
    est = {
        "viscous": (lpd_shifted(9.0), 1),
        "coulomb": (lpd_shifted(1.0), 2),
        "power": (lpd_shifted(0.5), 2),
        "viscous+coulomb": (lpd_shifted(0.0), 3),
    }
    # best viscous+coulomb; coulomb and power as good (viscous 6 behind with one
    # parameter less: not); coulomb simplest of the adequate, then the misfitting
    holds = {"coulomb": True, "power": True, "viscous+coulomb": True, "viscous": True}
    order = sampling_order(laws, est, holds.get, laws, small=REACH)
    assert order == ["coulomb", "viscous", "power", "viscous+coulomb"]
    assert sampling_order(laws, est, {"viscous+coulomb": True}.get, laws, small=REACH)[0] == (
        "viscous+coulomb"
    )
    # none adequate: the simplest as good; one kept back does not lead
    assert sampling_order(laws, est, lambda law: False, laws, small=REACH)[0] == "coulomb"
    kept = sampling_order(
        laws, est, holds.get, laws, small=REACH, leads=lambda law: law != "coulomb"
    )
    assert kept[0] == "power" and sorted(kept) == sorted(laws)
    # no finite estimate: the order given
    inf = {law: (np.full(N, -np.inf), 1) for law in laws}
    assert sampling_order(laws, inf, holds.get, laws, small=REACH) == laws
