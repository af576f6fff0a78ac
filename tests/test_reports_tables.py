"""Results as tables for people: symbols, units, intervals in the digits they support."""

from __future__ import annotations

import doctest

import pytest

pytest.importorskip("pandas")

from bayestribo.reports import tables


def test_the_examples_hold():
    assert doctest.testmod(tables).failed == 0


def test_a_classical_table_names_methods_in_words_and_gives_intervals():
    from _paths import RUNS

    from bayestribo import estimate_all

    run = RUNS / "glycerol-N0.31-r1.csv"
    if not run.is_file():
        pytest.skip("the bundled campaign data/ is absent")
    frame = tables.estimates_frame(estimate_all(run, name="r1"))
    assert "Feeny–Liang (x)" in frame.index and "least squares on Π, exact model" in frame.index
    assert list(frame.columns) == ["ζ [95 %]", "μ_k [95 %]", "friction share", "caveat"]
    text = " ".join(frame.to_numpy().ravel())
    assert "_" not in " ".join(frame.index) and "None" not in text and "nan" not in text
    zeta = frame.loc["least squares on Π, exact model", "ζ [95 %]"]
    assert zeta.count("[") == 1 and zeta.endswith("]")


def test_units_and_laws_read_as_words():
    assert tables.unit_text("signal length unit") == "signal unit"
    assert tables.law_text("viscous+quadratic") == "viscous + quadratic drag"
    assert tables.normal_interval(None, None) == "–"
    assert tables.normal_interval(0.5, None) == "0.5"
    assert tables.share_text(float("nan")) == "–"
