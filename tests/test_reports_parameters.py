"""Typed parameters of the report notebooks: read from the cell, values checked."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from bayestribo.reports import ReportError
from bayestribo.reports.parameters import ParameterError, check_value, parameter_specs

CELL = """# Parameters
steps: int = 10  # sampler steps
rate: float = 2.5  # sample rate [Hz]
name: str | None = None  # a name
loads: list[float] | None = None  # loads [N]
options: dict = {}  # keyword arguments
flag: bool = False  # a switch
anything = [1, "a"]
"""


def test_names_types_defaults_and_comments_are_read():
    specs = parameter_specs(CELL)
    assert list(specs) == ["steps", "rate", "name", "loads", "options", "flag", "anything"]
    assert specs["loads"].type == "list[float] | None" and specs["loads"].comment == "loads [N]"
    assert specs["rate"].default == 2.5 and specs["anything"].type == "any literal"


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("steps", 3),
        ("rate", 3),
        ("rate", 1e-3),
        ("name", "x"),
        ("name", None),
        ("loads", [1, 0.5]),
        ("options", {"a": 1}),
        ("flag", True),
        ("anything", object()),
    ],
)
def test_values_of_the_type_are_accepted(name, value):
    check_value(parameter_specs(CELL)[name], value)


@pytest.mark.parametrize(
    ("name", "value", "expected"),
    [
        ("steps", "5k", r"expected int, got '5k' \(str\)"),
        ("steps", 5.0, "expected int"),
        ("steps", True, "expected int"),
        ("rate", "fast", "expected float"),
        ("loads", 0.3, r"expected list\[float\] \| None"),
        ("loads", [0.3, "x"], r"expected list\[float\] \| None"),
        ("flag", 1, "expected bool"),
        ("options", [], "expected dict"),
    ],
)
def test_a_wrong_type_is_refused_naming_parameter_and_type(name, value, expected):
    with pytest.raises(ParameterError, match=f"parameter '{name}': {expected}"):
        check_value(parameter_specs(CELL)[name], value)


def test_a_parameter_error_is_a_report_error():
    assert issubclass(ParameterError, ReportError)


@pytest.mark.parametrize(
    ("cell", "message"),
    [
        ("x: int = 'a'  # default of the wrong type", "parameter 'x': expected int"),
        ("x: complex = 1  # unknown type", "annotation 'complex'"),
        ("x = y  # not a literal", "not a literal"),
        ("print(1)", "plain assignments only"),
        ("x: int", "plain assignments only"),
        ("x = (", "not valid Python"),
    ],
)
def test_a_malformed_cell_is_refused(cell, message):
    with pytest.raises(ParameterError, match=message):
        parameter_specs(cell)


@given(st.lists(st.floats(allow_nan=False) | st.integers(), max_size=5))
def test_any_list_of_numbers_is_a_list_of_floats(values):
    check_value(parameter_specs("x: list[float] = []  # numbers")["x"], values)


@given(st.text(max_size=10))
def test_no_string_is_an_int(text):
    with pytest.raises(ParameterError):
        check_value(parameter_specs("x: int = 0  # a count")["x"], text)
