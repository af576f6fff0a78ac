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
    zeta = frame.loc["Feeny–Liang (x)", "ζ [95 %]"]
    assert zeta.count("[") == 1 and zeta.endswith("]")
    # an interval the estimator says is too narrow (the peaks' noise only, correlated
    # residuals) does not support ten digits: four, and its half width said apart
    for method in ("non-successive peaks (v)", "least squares on Π, exact model"):
        cell = frame.loc[method, "ζ [95 %]"]
        value = cell.split("\u00a0")[0]
        assert cell.endswith("too narrow)") and len(value.lstrip("0.")) <= 4, cell


def test_units_and_laws_read_as_words():
    assert tables.unit_text("signal length unit") == "signal unit"
    # a number's unit in a report's tables is the command line's word for it
    from bayestribo.inference.quantities import unit_words

    for unit in (None, "", "1", "-", "y", "J", "signal length unit^2", "1/y"):
        assert tables.unit_text(unit) == unit_words(unit), unit
    assert tables.unit_text("1") == "dimensionless"
    assert tables.law_text("viscous+quadratic") == "viscous damping + quadratic drag"
    assert tables.normal_interval(None, None) == "–"
    assert tables.normal_interval(0.5, None) == "0.5"
    assert tables.share_text(float("nan")) == "–"


def test_an_unphysical_estimate_is_flagged_in_words_not_hidden():
    """A negative friction (Feeny–Liang and the non-successive peaks give one on the
    spring-and-disc recordings, where air drag grows with speed) is shown as it is and
    called unphysical; a negative ζ too."""
    from types import SimpleNamespace

    def estimate(**kw):
        base = {
            "method": "feeny_liang",
            "data": "displacement peaks",
            "zeta": 0.0066,
            "zeta_se": 8.5e-4,
            "mu_k": None,
            "mu_k_se": None,
            "friction_displacement": -1.09e-4,
            "friction_displacement_se": 1.0e-5,
            "friction_fraction": 1e-5,
            "notes": "",
        }
        return SimpleNamespace(**{**base, **kw})

    frame = tables.estimates_frame([estimate()], unit="m")
    row = frame.loc["Feeny–Liang (x)"]
    assert row["x_c [m] [95 %]"].startswith("-0.000109")  # the value, not "0 (at the bound)"
    assert row["caveat"] == "negative friction: unphysical, not a measurement"
    assert "negative ζ" in tables.caveat_text(estimate(zeta=-0.001))
    assert tables.caveat_text(estimate(friction_displacement=2e-4)) == "–"


def test_estimators_that_ignore_friction_are_labelled_so():
    from _paths import RUNS

    from bayestribo import estimate_all

    run = RUNS / "glycerol-N0.31-r1.csv"
    if not run.is_file():
        pytest.skip("the bundled campaign data/ is absent")
    table = estimate_all(run, name="r1")
    frame = tables.estimates_frame(table)
    decrement = frame.loc["logarithmic decrement (x)"]
    # ζ of the logarithmic decrement is twice the truth here: it ignores friction
    assert decrement["caveat"].startswith("ignores friction")
    labels = [tables.method_text(e, physics=True) for e in table]
    assert "logarithmic decrement (x), ignores friction" in labels
    assert "exponential envelope (x), ignores friction" in labels
    assert "least squares on Π, exact model" in labels  # it models friction


class _Fit:
    """A fit with one sampled parameter: uniform prior on [0, 1], posterior draws given."""

    law = "viscous+coulomb"

    def __init__(self, draws):
        import numpy as np

        from bayestribo.inference.priors import PriorSet, Uniform

        self.symbols, self.prior_sensitivity = {}, {}
        self._draws = np.asarray(draws, dtype=float)
        self.priors = PriorSet({"mu_s_ratio": Uniform(0.0, 1.0)})

    def samples(self, name):
        return self._draws


def _summary(draws):
    from bayestribo.summary import ParameterSummary

    return ParameterSummary.from_samples(draws)


def test_a_posterior_flat_over_its_prior_is_shown_as_a_bound_not_a_measurement():
    import numpy as np

    rng = np.random.default_rng(1)
    # flat over the prior where the data allow it (μ_s/μ_k up to 2.9 of a prior to 10),
    # as the stop of the motion bounds the static friction from above only
    flat = rng.uniform(0.0, 0.3, 4000)
    assert tables.prior_flatness(_Fit(flat), "mu_s") < tables.FLAT_KS
    text = tables.quantity_text(_Fit(flat), "mu_s", _summary(flat))
    assert text.startswith("not constrained by the data: μ_s < ")
    assert f"< {np.quantile(flat, 0.975):.2g} " in text
    # a posterior that the data narrow to a value is a measurement in the digit rule
    narrow = rng.normal(0.5, 0.029, 4000)
    s = _summary(narrow)
    assert tables.prior_flatness(_Fit(narrow), "mu_s") > 2 * tables.FLAT_KS
    assert tables.quantity_text(_Fit(narrow), "mu_s", s) == tables.interval_text(
        s.mean, *s.interval
    )


def test_a_static_friction_bounded_from_above_only_is_shown_as_a_bound():
    import numpy as np

    # highest at the prior's lower end, a soft fall to 0.6: not flat (the KS test misses
    # it), but the data bound it from above only (inference/flatness.py, end_density);
    # the fit's summary made it a bound, the report's table printed a measurement
    rng = np.random.default_rng(2)
    x = rng.uniform(0.0, 0.6, 40000)
    falling = x[rng.uniform(0.0, 1.0, x.size) < 1.0 - x / 0.6][:4000]
    fit = _Fit(falling)
    assert tables.prior_flatness(fit, "mu_s") > tables.FLAT_KS
    text = tables.quantity_text(fit, "mu_s", _summary(falling))
    assert text.startswith("not constrained by the data: μ_s < ")
    assert "bounded from above only" in text


def test_a_quantity_without_a_prior_of_its_own_has_no_flatness():
    assert tables.prior_flatness(_Fit([0.1, 0.2, 0.3]), "no_such_quantity") is None


@pytest.mark.parametrize(
    ("p", "text"), [(1.0, "> 0.999"), (0.9996, "> 0.999"), (0.0, "< 0.001"), (0.5, "0.500")]
)
def test_a_probability_at_its_end_is_not_said_as_certainty(p, text):
    assert tables.probability_text(p) == text


def test_an_energy_per_cycle_is_held_at_zero_below_and_other_quantities_are_not():
    assert tables.nonnegative_text("ΔE(A=1e-04 m)", 1e-7, -3e-7, 6e-7).startswith("0 (at the")
    assert "-" in tables.nonnegative_text("slope", 1e-7, -3e-7, 6e-7)


def test_prose_said_twice_is_prose_said_once():
    """A note's text goes through prose where it is made and again in kit.note: the
    law's words are said once ("the law viscous damping damping + Coulomb friction"
    once stood in the real-data report's notes)."""
    from bayestribo.model.laws import TERMS

    for name in TERMS:
        for text in (f"the law {name} holds", f"the law {name}+coulomb misfits /d/r_1.csv"):
            once = tables.prose(text, paths={"/d/r_1.csv": "r_1.csv"})
            assert tables.prose(once) == once, once
            assert f"law {tables.law_text(name)} " in once and f"{name}+" not in once
