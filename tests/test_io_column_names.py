"""The column names the package suggests read back as the column they were made from."""

from __future__ import annotations

import math

import pytest

from bayestribo.io.columns import QUANTITIES, UNITS, column_name, parse_column

#: Every (canonical column, unit) pair, spelled as sensor software heads a column.
CASES = [(canonical, unit) for canonical, units in UNITS.items() for unit in units]


@pytest.mark.parametrize(("canonical", "unit"), CASES)
def test_a_suggested_name_reads_back_as_its_label(canonical: str, unit: str) -> None:
    word = sorted(QUANTITIES[canonical], key=len)[-1].title()
    label = f"{word} ({unit})"
    parsed = parse_column(label)
    assert parsed is not None and parsed[0] == canonical
    name = column_name(label, *parsed)
    assert name.replace("_", "").isalnum(), name  # a name for --columns, not the label
    again = parse_column(name)
    assert again is not None and again[0] == canonical
    assert math.isclose(again[1], parsed[1], rel_tol=1e-15)


def test_an_axis_of_an_acceleration_keeps_its_axis() -> None:
    parsed = parse_column("Acceleration y (m/s²)")
    assert parsed == ("acceleration_y_m_per_s2", 1.0)
    assert column_name("Acceleration y (m/s²)", *parsed) == "acceleration_y_m_per_s2"


def test_the_files_spelling_of_a_unit_is_kept() -> None:
    assert column_name("Position (mm)", "displacement_m", 1e-3) == "displacement_mm"
    assert column_name("Angle (deg)", "angle_rad", math.pi / 180) == "angle_deg"
    assert column_name("Angular velocity (rpm)", *parse_column("Angular velocity (rpm)")) == (
        "angular_velocity_rpm"
    )
