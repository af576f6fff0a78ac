"""``law="auto"`` says when laws of other ΔE(A) shapes are as good as its verdict."""

from __future__ import annotations

import warnings

import pytest

from bayestribo.errors import MisfitWarning, ShapeUnresolvedWarning
from bayestribo.inference.auto import _warn_unresolved, shape_unresolved
from bayestribo.inference.records import LawComparison


def _comparison(as_good, adequate=True, inadequate=()):
    table = {
        law: {"adequate": law not in inadequate} for law in ("viscous", "coulomb", "quadratic")
    }
    return LawComparison(
        run_name="r",
        table=table,
        best=as_good[0],
        verdict=as_good[0],
        as_good=list(as_good),
        adequate=adequate,
    )


def _departures(**slopes):
    return {law: {"law_slope": slope} for law, slope in slopes.items()}


def test_a_law_of_another_shape_as_good_as_the_verdict_is_named():
    found = shape_unresolved(
        _comparison(["viscous", "coulomb"]), _departures(viscous=2.0, coulomb=1.0)
    )
    assert found == {"slopes": {"viscous": 2.0, "coulomb": 1.0}, "others": ["coulomb"]}


@pytest.mark.parametrize(
    ("as_good", "slopes", "kwargs"),
    [
        # the same shape within the tolerance (0.5)
        (["viscous", "quadratic"], {"viscous": 2.0, "quadratic": 2.45}, {}),
        # another shape, but behind the verdict (not as good)
        (["viscous"], {"viscous": 2.0, "coulomb": 1.0}, {}),
        # another shape as good, but that law misfits
        (["viscous", "coulomb"], {"viscous": 2.0, "coulomb": 1.0}, {"inadequate": ("coulomb",)}),
        # the verdict not adequate: the answer is already the turning points'
        (["viscous", "coulomb"], {"viscous": 2.0, "coulomb": 1.0}, {"adequate": False}),
    ],
)
def test_nothing_is_said_where_the_record_tells_the_shape_or_no_law_holds(as_good, slopes, kwargs):
    assert shape_unresolved(_comparison(as_good, **kwargs), _departures(**slopes)) is None


def test_the_warning_is_a_misfit_naming_both_laws_and_their_slopes():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _warn_unresolved(
            "run-1",
            "viscous",
            {"slopes": {"viscous": 2.0, "coulomb": 1.02}, "others": ["coulomb"]},
            True,
        )
    (w,) = caught
    assert issubclass(w.category, ShapeUnresolvedWarning)
    assert issubclass(w.category, MisfitWarning)  # fit exits 1
    text = str(w.message)
    assert "run-1" in text and "viscous (ΔE ∝ A^2.00)" in text and "coulomb (ΔE ∝ A^1.02)" in text
    assert "averaged" in text
