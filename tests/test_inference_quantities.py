"""What each quantity of a fit is, from the registry of dissipation terms."""

from __future__ import annotations

import math

import pytest

from bayestribo.inference.likelihood import NEAR_ZERO, departure_size
from bayestribo.inference.quantities import describe, unit_words
from bayestribo.model.laws import TERMS, get_law


@pytest.mark.parametrize("term", list(TERMS))
def test_every_registered_parameter_is_named_by_the_registry(term) -> None:
    law = get_law(term)
    names = [p.name for p in law.parameters]
    quantities = describe(names, law=law.name, sampled=set(names))
    for p in law.parameters:
        q = quantities[p.name]
        assert (q.symbol, q.label, q.sampled) == (p.symbol, p.label, True)
        assert q.title == f"{p.label} {p.symbol}"
        # a fit reports μ_k as the coefficient x_c k/N, a number (sampled in units of y)
        assert q.unit == ("1" if p.unit == "-" or p.name == "mu_k" else p.unit)


def test_the_displacement_takes_the_runs_unit() -> None:
    names = ["friction_displacement", "static_friction_displacement", "mu_k"]
    metres = describe(names, law="viscous+coulomb", metadata={"length_unit": "m"})
    assert metres["friction_displacement"].unit == "m"
    assert metres["friction_displacement"].title == "friction as displacement x_c"
    assert metres["mu_k"].unit == "1"  # the reported coefficient, not "y"
    unknown = describe(names, law="viscous+coulomb", metadata={"length_unit": "arbitrary"})
    assert unit_words(unknown["static_friction_displacement"].unit) == "signal unit"
    angle = describe(names, law="viscous+coulomb", metadata={"length_unit": "rad"})
    assert angle["friction_displacement"].symbol == "θ_c"
    assert angle["friction_displacement"].unit == "rad"


def test_y0_is_a_displacement_in_the_signals_unit_unless_scaled_by_the_load() -> None:
    # where the fit did not scale y = x/ℓ by ℓ = N/k, ℓ is one unit of the signal: y₀ is
    # the displacement at the window's start in that unit (it was labelled a
    # dimensionless amplitude: 3.3e6 "dimensionless" for a seismometer in counts)
    for metadata, what, unit in (
        ({"length_unit": "arbitrary"}, "displacement", "signal length unit"),
        ({"length_unit": "rad"}, "angle", "rad"),
        ({"length_unit": "m"}, "displacement", "m"),
    ):
        y0 = describe(["y0"], law="viscous+coulomb", metadata=metadata)["y0"]
        assert (y0.label, y0.unit) == (f"{what} at the window's start", unit), metadata
    # scaled by the load: y = x/ℓ, a number
    scaled = describe(
        ["y0"], law="viscous+coulomb", metadata={"length_unit": "m"}, friction_defined=True
    )["y0"]
    assert scaled.unit == "1" and "x₀/ℓ" in scaled.label


def test_y0_follows_the_fits_own_scaling():
    # a fit with a load and a mass (the bundled run) scales y by N/k, one in air (no
    # load) does not: the label is the fit's record, not a rule made again from metadata
    import warnings

    from bayestribo import fit, simulate

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        loaded = fit(simulate(seed=3), seed=1, max_steps=600)
        air = fit(simulate(seed=3).with_metadata(load_N=0.0), seed=1, max_steps=600)
    assert loaded.quantity_info()["y0"].unit == "1"
    assert air.quantity_info()["y0"].label == "displacement at the window's start"
    assert air.quantity_info()["y0"].unit == "m"


def test_units_recorded_by_the_fit_win_and_unknown_names_keep_their_name() -> None:
    quantities = describe(
        ["c2", "c2_SI", "mystery"], law="viscous+quadratic", units={"c2_SI": "kg/m"}
    )
    assert quantities["c2_SI"].unit == "kg/m" and quantities["c2_SI"].symbol == "c₂"
    assert quantities["c2"].unit == "1/y" and unit_words("1/y") == "1/y (y = x/ℓ)"
    assert (quantities["mystery"].symbol, quantities["mystery"].label) == ("mystery", "")


def test_dimensionless_units_read_as_such_and_others_as_written() -> None:
    for unit in ("1", "-", "", "y"):
        assert unit_words(unit) == "dimensionless"
    assert unit_words("s/m") == "s/m" and unit_words("signal length unit^2") == "signal unit²"


def _shape(relative: float, reference: float, largest: float = 1.0) -> dict[str, float]:
    return {
        "max_relative": relative,
        "max_relative_sd": abs(relative) / 10,
        "reference": reference,
        "largest": largest,
    }


def test_a_departure_from_a_fair_reference_is_in_percent() -> None:
    assert departure_size(_shape(0.0123, 0.4)) == "+1.23 % (± 0.12 %)"


@pytest.mark.parametrize(
    ("relative", "reference"), [(37.0, 1e-6), (0.3, 0.5 * NEAR_ZERO), (-2.0, 0.2)]
)
def test_a_departure_from_a_reference_near_zero_is_absolute(relative, reference) -> None:
    text = departure_size(_shape(relative, reference))
    assert "%" not in text.split(" in an increment")[0]  # no percent of almost nothing
    difference = relative * reference
    assert text == (
        f"{difference:+.3g} (± {abs(difference) / 10:.2g}) in an increment of Π "
        f"({100 * abs(difference):.2g} % of the largest)"
    )


def test_the_absolute_departure_is_the_largest_in_pi_not_at_the_relative_ones_place() -> None:
    # the law's increment is zero where the relative departure is largest (the model's
    # motion ended): the departure that matters is the largest in Π, elsewhere
    shape = {**_shape(1e6, 0.0), "max_absolute": -2.5e-4, "max_absolute_sd": 4e-5}
    text = departure_size(shape)
    assert text == "-0.00025 (± 4e-05) in an increment of Π (0.025 % of the largest)"


def test_a_departure_saved_before_its_reference_was_recorded_stays_relative() -> None:
    old = {"max_relative": 0.05, "max_relative_sd": 0.01}
    assert departure_size(old) == "+5 % (± 1 %)"
    assert math.isnan(float(old.get("reference", math.nan)))
