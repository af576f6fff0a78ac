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


@pytest.mark.parametrize(
    ("label", "canonical", "factor"),
    [
        ("Zeit [s]", "time_s", 1.0),
        ("Weg [mm]", "displacement_m", 1e-3),
        ("Auslenkung (µm)", "displacement_m", 1e-6),
        ("Geschwindigkeit [m/s]", "velocity_m_per_s", 1.0),
        ("temps (ms)", "time_s", 1e-3),
        ("déplacement (mm)", "displacement_m", 1e-3),
        ("vitesse (mm/s)", "velocity_m_per_s", 1e-3),
        ("tempo [s]", "time_s", 1.0),
        ("spostamento [cm]", "displacement_m", 1e-2),
        ("velocità [m/s]", "velocity_m_per_s", 1.0),
        ("tiempo (s)", "time_s", 1.0),
        ("posición (m)", "displacement_m", 1.0),
        ("Winkel [deg]", "angle_rad", math.pi / 180),
        ("Beschleunigung [m/s^2]", "acceleration_m_per_s2", 1.0),
    ],
)
def test_a_lab_software_in_another_language_heads_its_columns_readably(
    label: str, canonical: str, factor: float
) -> None:
    parsed = parse_column(label)
    assert parsed is not None and parsed[0] == canonical
    assert math.isclose(parsed[1], factor, rel_tol=1e-15)


def test_a_german_export_with_decimal_commas_reads_with_no_option(tmp_path) -> None:
    from bayestribo import read_run

    path = tmp_path / "messung.csv"
    rows = [f"{k / 1000:.3f};{5 * math.cos(k / 40):.5f}".replace(".", ",") for k in range(400)]
    path.write_text("Zeit [s];Weg [mm]\n" + "\n".join(rows) + "\n", encoding="utf-8")
    run = read_run(path)
    assert run.time[1] == pytest.approx(1e-3) and run.displacement[0] == pytest.approx(5e-3)
