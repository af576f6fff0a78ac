"""Integrating a drag's creep to rest moves no Π that was defined before.

``tests/law_pi_before_creep.npz`` holds Π of every registered law (and a power drag
beside a viscous one) on a parameter grid, as the tree before the creep's integration
computed it (``tests/_law_pi_cases.py``, which draws the grid and says how the fixture
is made): 14 laws × 5 settings (to the end of motion and to a record's end, a start in
motion, the optimiser's coarse steps, the closed form where the law has one) × 24 rows.
"""

from __future__ import annotations

import json

import numpy as np
from _law_pi_cases import FIXTURE, ROWS, TAU, Y0


def _fixture() -> tuple[np.ndarray, np.ndarray, list[dict]]:
    data = np.load(FIXTURE)
    return data["before"], data["creep"], json.loads(str(data["cases"]))


#: How far a row may move on another CPU, relative to its Π(0): the fixture was made on
#: an AVX-512 machine, and a law compiled for another (AVX2: numba's pow and exp, numpy's
#: SIMD kernels) rounds each step's last bit otherwise, which an integration carries to
#: at most ~1e-14 of Π(0) (64 ulp, the power laws); a creep's ∫E moves a row by 1e-10
#: and more. On one machine a row is the same to the bit, or 1 ulp (a law compiled
#: afresh or loaded from the cache, ``cubic`` row 18).
_CPU_REL = 1e-13


def _kept(now: np.ndarray, before: np.ndarray) -> bool:
    """Equal within :data:`_CPU_REL` of the row's Π(0)."""
    return bool(np.all(np.abs(now - before) <= _CPU_REL * abs(before[0])))


def _now(case: dict, creep_end: float | None = None) -> np.ndarray:
    from bayestribo.model.laws import get_law

    law = get_law(case["law"])
    tau_end = None if np.isinf(case["tau_end"]) else float(case["tau_end"])
    values = {k: np.asarray(v, dtype=float) for k, v in case["values"].items()}
    return law.pi_grid(
        TAU,
        values,
        np.full(ROWS, Y0),
        case["yp0"],
        tau_end,
        reference=Y0,
        method=case["method"],
        steps=case["steps"],
        creep_end=creep_end,
    )


def test_every_row_defined_before_is_the_same():
    """Every row the older tree left finite, and did not end by a creep, is the same
    (to the bit on the fixture's machine; within :data:`_CPU_REL` on another CPU); a row
    it ended by a creep whose ∫E it took from the quasi-static balance (at most 1e-8 of
    Π(0), within a factor 2) moves by at most 3e-8 of Π(0); a row it left NaN may now be
    finite (a creep integrated), never the other way."""
    before, creep, cases = _fixture()
    finite_before = np.isfinite(before).all(axis=-1)
    same = 0
    for b, case in enumerate(cases):
        now = _now(case)
        for r in range(ROWS):
            if not finite_before[b, r]:
                continue
            assert np.isfinite(now[r]).all(), (case["law"], b, r)
            if creep[b, r]:
                assert np.max(np.abs(now[r] - before[b, r])) <= 3e-8 * before[b, r, 0]
            else:
                assert _kept(now[r], before[b, r]), (case["law"], case, r)
                same += 1
    # the grid holds rows of every kind: most defined before, some refused
    assert same > 0.7 * finite_before.size
    assert (~finite_before).sum() > 0


def test_a_creep_end_moves_no_row_defined_before():
    """A creep's end inside the grid (τ = 50, where a record's motion would have been
    seen to stop) moves no row the older tree left finite and did not end by a creep,
    of any law, setting or method, by a bit: only a creep reads it."""
    before, creep, cases = _fixture()
    keep = np.isfinite(before).all(axis=-1) & ~creep
    for b, case in enumerate(cases):
        without = _now(case)
        now = _now(case, creep_end=50.0)
        for r in np.flatnonzero(keep[b]):
            np.testing.assert_array_equal(now[r], without[r], err_msg=f"{case} row {r}")
