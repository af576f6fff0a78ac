"""Exports of sensor software: PASCO Capstone, Vernier, Polytec; read right or refused
with a fix that works when followed."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bayestribo import read_run
from bayestribo.cli import main
from bayestribo.errors import ReadingWarning, RunFormatError
from bayestribo.io.sidecar import sidecar_path, write_sidecar

RATE = 1000.0
T = (np.arange(3000) / RATE).tolist()
X = (1e-2 * np.exp(-0.4 * np.asarray(T)) * np.cos(2 * np.pi * 3.0 * np.asarray(T))).tolist()
V = np.gradient(np.asarray(X), np.asarray(T)).tolist()
META = {"natural_frequency_Hz": 3.0}


def _write(path: Path, header: str, rows: list[str], encoding: str = "utf-8") -> Path:
    path.write_text(header + "\n" + "\n".join(rows) + "\n", encoding=encoding)
    write_sidecar(META, sidecar_path(path))
    return path


def test_pasco_run_labels_are_taken_off_and_acceleration_is_not_read(tmp_path: Path) -> None:
    header = (
        '"Time (s) Run #1","Position (m) Run #1","Velocity (m/s) Run #1",'
        '"Acceleration (m/s²) Run #1"'
    )
    rows = [f"{t!r},{x!r},{v!r},0.5" for t, x, v in zip(T, X, V, strict=True)]
    path = _write(tmp_path / "capstone.csv", header, rows)
    with pytest.warns(ReadingWarning, match=r"\['Acceleration \(m/s²\)'\] not read"):
        run = read_run(path)
    np.testing.assert_array_equal(run.displacement, X)
    np.testing.assert_array_equal(run.velocity, V)


def test_runs_side_by_side_are_refused_with_the_columns_that_read_each(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    """Run #2 is shorter: its cells are empty in the last rows."""
    n2 = 2000
    header = (
        "Time (s) Run #1,Position (mm) Run #1,Time (s) Run #2,Position (mm) Run #2,"
        "Velocity (mm/s) Run #2"
    )
    rows = []
    for i, (t, x) in enumerate(zip(T, X, strict=True)):
        second = f"{T[i]!r},{2e3 * X[i]!r},{2e3 * V[i]!r}" if i < n2 else ",,"
        rows.append(f"{t!r},{1e3 * x!r},{second}")
    path = _write(tmp_path / "two.csv", header, rows)
    with pytest.raises(RunFormatError, match=r"2 runs side by side \(Run #1, Run #2\)") as info:
        read_run(path)
    message = str(info.value)
    assert "Run #1: columns=['time_s', 'displacement_mm', 'ignore', 'ignore', 'ignore']" in message
    # Followed in Python ...
    second = read_run(
        path, columns=["ignore", "ignore", "time_s", "displacement_mm", "velocity_mm_per_s"]
    )
    assert second.time.size == n2
    np.testing.assert_allclose(second.displacement, 2 * np.asarray(X[:n2]), rtol=1e-15)
    # ... and on the command line, where the message spells the option.
    assert main(["inspect", str(path)]) == 2
    err = capsys.readouterr().err
    assert "Run #2: --columns - - t displacement_mm velocity_mm_per_s" in err
    fix = err.split("Run #2: ")[1].split()[1:]
    assert main(["inspect", str(path), "--columns", *fix, "--json"]) == 0


def test_vernier_latest_labels_and_centimetres(tmp_path: Path) -> None:
    header = '"Latest: Time (s)","Latest: Position (cm)","Latest: Velocity (cm/s)"'
    rows = [f"{t!r},{100 * x!r},{100 * v!r}" for t, x, v in zip(T, X, V, strict=True)]
    run = read_run(_write(tmp_path / "vernier.csv", header, rows))
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15, atol=0)
    np.testing.assert_allclose(run.velocity, V, rtol=1e-15, atol=0)


def test_a_row_of_units_below_the_names(tmp_path: Path) -> None:
    rows = [f"{t!r}\t{1e3 * x!r}\t{1e3 * v!r}" for t, x, v in zip(T, X, V, strict=True)]
    run = read_run(_write(tmp_path / "units.txt", "Time\tPosition\tVelocity\ns\tmm\tmm/s", rows))
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15, atol=0)
    assert run.time.size == len(T)


def test_polytec_brackets_and_micro_sign_in_windows_1252(tmp_path: Path) -> None:
    rows = [f"{t!r}\t{1e6 * x!r}\t{1e3 * v!r}" for t, x, v in zip(T, X, V, strict=True)]
    header = "Time [s]\tVib Displacement [µm]\tVib Velocity [mm/s]"
    path = _write(tmp_path / "psv.txt", header.replace("Vib ", ""), rows, encoding="cp1252")
    with pytest.warns(ReadingWarning, match="not UTF-8"):
        run = read_run(path)
    np.testing.assert_allclose(run.displacement, X, rtol=1e-15, atol=0)
    run = read_run(path, encoding="cp1252")
    np.testing.assert_allclose(run.velocity, V, rtol=1e-15, atol=0)


def test_a_column_of_no_known_quantity_is_still_an_error(tmp_path: Path) -> None:
    rows = [f"{t!r},{x!r},1" for t, x in zip(T, X, strict=True)]
    path = _write(tmp_path / "odd.csv", "Time (s),Position (m),Gizmo (V)", rows)
    with pytest.raises(RunFormatError, match="unknown column 'Gizmo"):
        read_run(path)
