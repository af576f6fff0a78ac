"""``benchmarks/sweep_compare.py``: two misspecification sweeps of the same records run by
run; and ``benchmarks/misspecification.py --first-run``: a sweep's later runs alone."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _module(name):
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    return module


@pytest.fixture(scope="module")
def compare():
    return _module("sweep_compare")


@pytest.fixture(scope="module")
def sweep():
    return _module("misspecification")


def _run(index, z_zeta, z_mu, warnings=(), case="gain"):
    z = {"zeta": z_zeta, "mu_k": z_mu}
    return {
        "case": case,
        "noise": 10.0,
        "index": index,
        "entropy": [2010, 0, 1000, index],
        "warnings": list(warnings),
        "converged": True,
        "fit_seconds": 1.0,
        "z": z,
        "covered": {p: abs(v) < 1.96 for p, v in z.items()},
    }


def _runs(*runs):
    return {(r["case"], r["noise"], r["index"]): r for r in runs}


def test_the_outcome_of_a_run(compare):
    assert compare.outcome(_run(0, 0.1, -0.2)) == "covered"
    assert compare.outcome(_run(0, 2.5, 0.0)) == "missed"
    assert compare.outcome(_run(0, 2.5, 0.0, ["MisfitWarning"])) == "flagged"
    assert compare.outcome(_run(0, 3.5, 0.0)) == "silent"
    assert compare.outcome(_run(0, 3.5, 0.0, ["MisfitWarning"])) == "flagged"
    assert compare.outcome({**_run(0, 0, 0), "refused": "ValueError: no"}) == "refused"


def test_a_run_newly_silently_wrong_or_refused_is_listed_by_index(compare):
    before = _runs(_run(10, 0.1, 0.2), _run(11, -0.5, 0.4), _run(12, 1.0, -1.0))
    after = _runs(_run(10, 0.1, 0.2), _run(11, -3.6, 0.4), {**_run(12, 0, 0), "refused": "E: x"})
    [row] = compare.compare(before, after)
    assert row["runs"] == 3 and row["indices"] == [10, 12]
    assert row["after"]["silently_wrong"] == 1 and row["after"]["refused"] == 1
    assert row["runs_moved"] == 1  # the refused run has no z to move
    assert row["largest_dz"] == pytest.approx(3.1)
    changed = {c["index"]: (c["before"], c["after"]) for c in row["changed"]}
    assert changed == {11: ("covered", "silent"), 12: ("covered", "refused")}


def test_only_the_runs_in_both_sweeps_are_compared(compare):
    before = _runs(*(_run(i, 0.0, 0.0) for i in range(20)))
    after = _runs(*(_run(i, 0.0, 0.5) for i in range(10, 20)), _run(3, 0.0, 0.0, case="delay"))
    [row] = compare.compare(before, after)
    assert row["case"] == "gain" and row["runs"] == 10 and row["indices"] == [10, 19]
    assert row["runs_moved"] == 10 and row["changed"] == []


def test_a_sweeps_later_runs_are_the_whole_sweeps_same_runs(sweep):
    whole = sweep.run_indices(["clean", "gain"], [10.0, 30.0], 20, 100)
    later = sweep.run_indices(["clean", "gain"], [10.0, 30.0], 20, 100, first=10)
    assert set(later) <= set(whole)
    assert {i for c, n, i in later if c == "gain"} == set(range(10, 20))
    assert {i for c, n, i in later if c == "clean"} == set(range(10, 100))
    assert len(whole) - len(later) == 2 * 2 * 10
